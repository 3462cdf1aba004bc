//! Centroid alignment (CA), paper eq. (1): `R_cent = argmin_R Σ_i ‖C_Yi − R(C_Xi)‖²`, solved in
//! closed form (Kabsch, no scale, reflection-safe) from the CBCT tooth centroids onto the IOS
//! tooth centroids matched by FDI number.

use crate::mesh::TriMesh;
use crate::{Error, Result, Rigid};
use glam::{DMat3, DVec3};
use nalgebra::Matrix3;
use std::collections::BTreeMap;

/// Weighted least-squares rigid fit `argmin_R Σ w_k ‖dst_k − R(src_k)‖²` (Kabsch without scale;
/// the sign correction keeps a proper rotation). Needs three non-collinear points.
pub fn kabsch(src: &[DVec3], dst: &[DVec3], weights: Option<&[f64]>) -> Result<Rigid> {
    if src.len() != dst.len() {
        return Err(Error::InvalidArgument(format!(
            "{} source points but {} target points",
            src.len(),
            dst.len()
        )));
    }
    let w = |k: usize| weights.map_or(1.0, |w| w[k]);
    let wsum: f64 = (0..src.len()).map(w).sum();
    if src.len() < 3 || wsum <= 0.0 {
        return Err(Error::MissingData(format!(
            "a rigid fit needs at least 3 weighted point pairs, got {}",
            src.len()
        )));
    }
    let cs = (0..src.len()).fold(DVec3::ZERO, |a, k| a + src[k] * w(k)) / wsum;
    let cd = (0..dst.len()).fold(DVec3::ZERO, |a, k| a + dst[k] * w(k)) / wsum;
    let mut h = Matrix3::<f64>::zeros();
    let mut spread = 0.0f64;
    for k in 0..src.len() {
        let a = src[k] - cs;
        let b = dst[k] - cd;
        spread = spread.max(a.length());
        let wk = w(k);
        for i in 0..3 {
            for j in 0..3 {
                h[(i, j)] += wk * a[i] * b[j];
            }
        }
    }
    let svd = h.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => {
            return Err(Error::DidNotConverge(
                "SVD of the cross-covariance failed".into(),
            ));
        }
    };
    let s = svd.singular_values;
    // nalgebra does not sort singular values: find the largest and smallest by index.
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
    if spread == 0.0 || s[order[1]] <= 1e-9 * s[order[0]].max(f64::MIN_POSITIVE) {
        return Err(Error::MissingData(
            "the points are collinear (or coincide): a rotation is not determined".into(),
        ));
    }
    let v = vt.transpose();
    let mut fix = Matrix3::<f64>::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        // Reflection: flip the direction of the smallest singular value.
        fix[(order[2], order[2])] = -1.0;
    }
    let r = v * fix * u.transpose();
    let rot = DMat3::from_cols(
        DVec3::new(r[(0, 0)], r[(1, 0)], r[(2, 0)]),
        DVec3::new(r[(0, 1)], r[(1, 1)], r[(2, 1)]),
        DVec3::new(r[(0, 2)], r[(1, 2)], r[(2, 2)]),
    );
    Ok(Rigid::new(rot, cd - rot * cs))
}

/// Vertex centroid of a mesh (the paper's `C_X`), or its area-weighted centroid.
pub fn mesh_centroid(mesh: &TriMesh, area_weighted: bool) -> Option<DVec3> {
    if !area_weighted {
        return crate::geom::centroid(&mesh.positions);
    }
    let mut sum = DVec3::ZERO;
    let mut area = 0.0;
    for f in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(f);
        let w = 0.5 * (b - a).cross(c - a).length();
        sum += (a + b + c) * (w / 3.0);
        area += w;
    }
    if area > 0.0 {
        Some(sum / area)
    } else {
        crate::geom::centroid(&mesh.positions)
    }
}

/// Eq. (1): rigid fit of CBCT centroids onto IOS centroids over the teeth both hold.
/// Fails with [`Error::MissingData`] naming the teeth when fewer than three are shared or their
/// centroids are collinear.
pub fn centroid_alignment(
    cbct_centroids: &BTreeMap<u8, DVec3>,
    ios_centroids: &BTreeMap<u8, DVec3>,
) -> Result<Rigid> {
    let shared: Vec<u8> = cbct_centroids
        .keys()
        .filter(|k| ios_centroids.contains_key(k))
        .copied()
        .collect();
    if shared.len() < 3 {
        return Err(Error::MissingData(format!(
            "centroid alignment needs at least 3 teeth present in both IOS and CBCT; shared: {:?} \
             (IOS has {:?}, CBCT has {:?})",
            shared,
            ios_centroids.keys().collect::<Vec<_>>(),
            cbct_centroids.keys().collect::<Vec<_>>()
        )));
    }
    let src: Vec<DVec3> = shared.iter().map(|k| cbct_centroids[k]).collect();
    let dst: Vec<DVec3> = shared.iter().map(|k| ios_centroids[k]).collect();
    kabsch(&src, &dst, None).map_err(|e| match e {
        Error::MissingData(_) => Error::MissingData(format!(
            "the centroids of the shared teeth {shared:?} are collinear: add a tooth off the line \
             or supply an initial transform"
        )),
        e => e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_transform_without_reflection() {
        let t = Rigid::from_axis_angle_about(
            DVec3::new(0.3, -1.0, 0.5),
            2.5,
            DVec3::new(4.0, 1.0, -2.0),
        );
        let src = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 1.0, 0.0),
            DVec3::new(3.0, 8.0, 0.5),
            DVec3::new(-4.0, 5.0, 1.0),
        ];
        let dst: Vec<DVec3> = src.iter().map(|p| t.apply(*p)).collect();
        let est = kabsch(&src, &dst, None).unwrap();
        assert!(est.is_rigid(1e-10));
        for p in src {
            assert!((est.apply(p) - t.apply(p)).length() < 1e-9);
        }
        // A mirrored target still yields a proper rotation.
        let mirrored: Vec<DVec3> = dst.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
        let m = kabsch(&src, &mirrored, None).unwrap();
        assert!(m.is_rigid(1e-10));
    }

    #[test]
    fn too_few_or_collinear_is_missing_data() {
        let mut c = BTreeMap::new();
        let mut i = BTreeMap::new();
        for (k, x) in [(11u8, 0.0), (12, 10.0)] {
            c.insert(k, DVec3::new(x, 0.0, 0.0));
            i.insert(k, DVec3::new(x, 0.0, 0.0));
        }
        i.insert(13, DVec3::ONE);
        let e = centroid_alignment(&c, &i).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::MissingData);
        assert!(e.to_string().contains("[11, 12]"), "{e}");
        c.insert(13, DVec3::new(20.0, 0.0, 0.0));
        i.insert(13, DVec3::new(20.0, 0.0, 0.0));
        let e = centroid_alignment(&c, &i).unwrap_err();
        assert!(e.to_string().contains("collinear"), "{e}");
    }
}
