//! Rigid transforms (rotation + translation), f64.

use glam::{DMat3, DMat4, DQuat, DVec3};

/// A rigid transform `p ↦ rot · p + trans`, `rot` a proper rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rigid {
    /// Rotation part (orthonormal, determinant +1).
    pub rot: DMat3,
    /// Translation part, millimetres.
    pub trans: DVec3,
}

impl Default for Rigid {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Rigid {
    /// The identity transform.
    pub const IDENTITY: Rigid = Rigid {
        rot: DMat3::IDENTITY,
        trans: DVec3::ZERO,
    };

    /// Builds a transform from a rotation and a translation.
    pub fn new(rot: DMat3, trans: DVec3) -> Self {
        Self { rot, trans }
    }

    /// A pure translation.
    pub fn from_translation(trans: DVec3) -> Self {
        Self {
            rot: DMat3::IDENTITY,
            trans,
        }
    }

    /// Rotation by `angle` radians about the unit `axis` through the point `center`.
    pub fn from_axis_angle_about(axis: DVec3, angle: f64, center: DVec3) -> Self {
        let rot = DMat3::from_axis_angle(axis.normalize(), angle);
        Self {
            rot,
            trans: center - rot * center,
        }
    }

    /// Small-angle update from a 6-vector `[rx, ry, rz, tx, ty, tz]` (axis-angle vector, exact
    /// rotation via Rodrigues, not the linearised matrix).
    pub fn from_twist(w: DVec3, t: DVec3) -> Self {
        let angle = w.length();
        let rot = if angle > 0.0 {
            DMat3::from_axis_angle(w / angle, angle)
        } else {
            DMat3::IDENTITY
        };
        Self { rot, trans: t }
    }

    /// Applies the transform to a point.
    #[inline]
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.rot * p + self.trans
    }

    /// Applies only the rotation (for normals and directions).
    #[inline]
    pub fn apply_vector(&self, v: DVec3) -> DVec3 {
        self.rot * v
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        let rt = self.rot.transpose();
        Self {
            rot: rt,
            trans: -(rt * self.trans),
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Rigid) -> Self {
        Self {
            rot: self.rot * other.rot,
            trans: self.rot * other.trans + self.trans,
        }
    }

    /// Rotation angle in radians (0..π).
    pub fn angle(&self) -> f64 {
        let c = ((self.rot.x_axis.x + self.rot.y_axis.y + self.rot.z_axis.z - 1.0) * 0.5)
            .clamp(-1.0, 1.0);
        c.acos()
    }

    /// Re-orthonormalises the rotation (after many compositions).
    pub fn orthonormalized(&self) -> Self {
        let q = DQuat::from_mat3(&self.rot).normalize();
        Self {
            rot: DMat3::from_quat(q),
            trans: self.trans,
        }
    }

    /// The 4×4 homogeneous matrix, row-major (as in the report and the C ABI).
    pub fn to_row_major(&self) -> [f64; 16] {
        let m = DMat4::from_cols(
            self.rot.x_axis.extend(0.0),
            self.rot.y_axis.extend(0.0),
            self.rot.z_axis.extend(0.0),
            self.trans.extend(1.0),
        );
        // glam stores columns; transposing gives rows in memory order.
        m.transpose().to_cols_array()
    }

    /// Builds a transform from a row-major 4×4 matrix. The rotation block is taken as is; use
    /// [`Rigid::is_rigid`] to check it.
    pub fn from_row_major(m: &[f64; 16]) -> Self {
        let rows = DMat4::from_cols_array(m).transpose();
        Self {
            rot: DMat3::from_cols(
                rows.x_axis.truncate(),
                rows.y_axis.truncate(),
                rows.z_axis.truncate(),
            ),
            trans: rows.w_axis.truncate(),
        }
    }

    /// True when the rotation block is orthonormal with determinant +1 (within `tol`) and all
    /// entries are finite.
    pub fn is_rigid(&self, tol: f64) -> bool {
        let r = self.rot;
        let rtr = r.transpose() * r;
        let cols = [rtr.x_axis, rtr.y_axis, rtr.z_axis];
        let ident = [DVec3::X, DVec3::Y, DVec3::Z];
        r.is_finite()
            && self.trans.is_finite()
            && cols
                .iter()
                .zip(ident.iter())
                .all(|(c, i)| (*c - *i).abs().max_element() <= tol)
            && (r.determinant() - 1.0).abs() <= tol
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_major_round_trip_and_layout() {
        let t = Rigid::from_axis_angle_about(
            DVec3::new(1.0, 2.0, 3.0),
            0.7,
            DVec3::new(4.0, -1.0, 2.0),
        );
        let m = t.to_row_major();
        // Translation sits in the last column of each row.
        assert_eq!(m[3], t.trans.x);
        assert_eq!(m[7], t.trans.y);
        assert_eq!(m[11], t.trans.z);
        assert_eq!(&m[12..], &[0.0, 0.0, 0.0, 1.0]);
        let back = Rigid::from_row_major(&m);
        assert_eq!(back, t);
        assert!(t.is_rigid(1e-12));
    }

    #[test]
    fn inverse_and_compose() {
        let a = Rigid::from_axis_angle_about(DVec3::Z, 0.3, DVec3::new(1.0, 0.0, 0.0));
        let b = Rigid::from_twist(DVec3::new(0.1, -0.2, 0.05), DVec3::new(3.0, 2.0, 1.0));
        let p = DVec3::new(0.5, -7.0, 2.5);
        let q = a.compose(&b).apply(p);
        assert!((q - a.apply(b.apply(p))).length() < 1e-12);
        assert!((a.inverse().apply(a.apply(p)) - p).length() < 1e-12);
        assert!((b.angle() - DVec3::new(0.1, -0.2, 0.05).length()).abs() < 1e-12);
    }
}
