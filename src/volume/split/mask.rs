//! One jaw's teeth mask cropped from a label volume: its occupancy and its surface (points on
//! the mask's 0.5 level with outward normals).

use crate::volume::LabelVolume;
use glam::{DMat3, DMat4, DVec3};

/// A binary mask in a padded box of a label volume.
#[derive(Clone, Debug)]
pub(crate) struct JawMask {
    /// Voxels of the box along i, j, k.
    pub dims: [usize; 3],
    /// Index in the volume of the box's voxel (0, 0, 0) (may be one below the volume: padding).
    pub lo: [i64; 3],
    /// Box voxel index → world millimetres.
    pub to_world: DMat4,
    /// True for voxels of the mask; the box's outer layer is always false.
    pub inside: Vec<bool>,
}

/// The six face neighbours as index steps.
pub(crate) const FACES: [[i64; 3]; 6] = [
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
];

impl JawMask {
    /// The voxels of `vol` labelled `label`, in their bounding box padded by one voxel; `None`
    /// when the label is absent.
    pub fn from_volume(vol: &LabelVolume, label: u16) -> Option<JawMask> {
        let (blo, bhi) = *vol.label_boxes().get(&label)?;
        let lo: [i64; 3] = std::array::from_fn(|a| blo[a] as i64 - 1);
        let dims: [usize; 3] = std::array::from_fn(|a| bhi[a] - blo[a] + 3);
        let mut inside = vec![false; dims[0] * dims[1] * dims[2]];
        for k in 1..dims[2] - 1 {
            for j in 1..dims[1] - 1 {
                let row = vol.idx(0, (j as i64 + lo[1]) as usize, (k as i64 + lo[2]) as usize);
                for i in 1..dims[0] - 1 {
                    let vi = (i as i64 + lo[0]) as usize;
                    inside[i + dims[0] * (j + dims[1] * k)] = vol.labels[row + vi] == label;
                }
            }
        }
        let shift = DMat4::from_translation(DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64));
        Some(JawMask {
            dims,
            lo,
            to_world: vol.voxel_to_world * shift,
            inside,
        })
    }

    /// Linear index of box voxel (i, j, k).
    #[cfg(test)]
    pub fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Box voxel (i, j, k) of a linear index.
    #[inline]
    pub fn ijk(&self, id: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [id % nx, (id / nx) % ny, id / (nx * ny)]
    }

    /// The linear index of the face neighbour of `id` along `step` (the box's outer layer is
    /// never inside, so callers only step from inside voxels and stay in the box).
    #[inline]
    pub fn step(&self, id: usize, step: [i64; 3]) -> usize {
        let s = step[0] + self.dims[0] as i64 * (step[1] + self.dims[1] as i64 * step[2]);
        (id as i64 + s) as usize
    }

    /// World position of a box voxel centre.
    pub fn world(&self, id: usize) -> DVec3 {
        let [i, j, k] = self.ijk(id);
        self.to_world
            .transform_point3(DVec3::new(i as f64, j as f64, k as f64))
    }

    /// Number of inside voxels.
    #[cfg(test)]
    pub fn count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// Points on the mask's 0.5 level (the centre of every face between an inside and an
    /// outside voxel) with the outward unit normal of the inside voxel there (the gradient of
    /// the occupancy over its 3×3×3 neighbourhood, in world coordinates), in voxel order.
    pub fn surface_points(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let lin = DMat3::from_mat4(self.to_world);
        let normal_map = lin.inverse().transpose();
        let mut pts = Vec::new();
        let mut normals = Vec::new();
        for id in 0..self.inside.len() {
            if !self.inside[id] {
                continue;
            }
            let out: Vec<[i64; 3]> = FACES
                .iter()
                .copied()
                .filter(|&f| !self.inside[self.step(id, f)])
                .collect();
            if out.is_empty() {
                continue;
            }
            let n = (normal_map * self.outward_gradient(id)).normalize_or_zero();
            let c = self.world(id);
            for f in out {
                let d = DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64);
                let n = if n == DVec3::ZERO {
                    (normal_map * d).normalize()
                } else {
                    n
                };
                pts.push(c + lin * (0.5 * d));
                normals.push(n);
            }
        }
        (pts, normals)
    }

    /// Σ over the 26 neighbours of (outside − inside)·offset, in voxel index space.
    fn outward_gradient(&self, id: usize) -> DVec3 {
        let mut g = DVec3::ZERO;
        for dk in -1..=1i64 {
            for dj in -1..=1i64 {
                for di in -1..=1i64 {
                    if !self.inside[self.step(id, [di, dj, dk])] {
                        g += DVec3::new(di as f64, dj as f64, dk as f64);
                    }
                }
            }
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Frame;

    #[test]
    fn surface_points_lie_between_inside_and_outside_voxels() {
        // A 7×7×7 cube of 0.3/0.3/0.5 mm voxels.
        let dims = [9, 9, 9];
        let mut labels = vec![0u16; 9 * 9 * 9];
        for k in 1..8 {
            for j in 1..8 {
                for i in 1..8 {
                    labels[i + 9 * (j + 9 * k)] = 4;
                }
            }
        }
        let v =
            LabelVolume::with_spacing(dims, [0.3, 0.3, 0.5], [0.0; 3], Frame::Lps, labels).unwrap();
        let m = JawMask::from_volume(&v, 4).unwrap();
        assert_eq!(m.dims, [9, 9, 9]);
        assert_eq!(m.count(), 343);
        let (p, n) = m.surface_points();
        // One point per boundary face: 6 sides of 7×7 faces.
        assert_eq!(p.len(), 6 * 49);
        assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-9));
        // The top face sits half a voxel above the top voxel centres (z = 7 × 0.5 + 0.25).
        let top = p.iter().map(|q| q.z).fold(f64::MIN, f64::max);
        assert!((top - 3.75).abs() < 1e-9, "{top}");
        // Normals point outward: away from the cube's centre.
        let c = DVec3::new(1.2, 1.2, 2.0);
        assert!(p.iter().zip(&n).all(|(q, n)| (*q - c).dot(*n) > 0.0));
    }
}
