//! Hand-made cut teeth for the remedies' unit tests.

use super::FuseOptions;
use super::tooth::{CutTooth, cut_tooth};
use crate::geom::Rigid;
use crate::mesh::TriMesh;
use crate::mesh::fixtures::ellipsoid;

/// A tooth standing along z, cut with the default options: a CBCT ellipsoid and, as the IOS
/// crown, the top of a finer one above z = 4, or above z = `notch_top` within `notch_deg` of
/// +x (a crown whose label climbs a contact's flank there, vertically; 0° for none).
pub(super) fn ellipsoid_tooth(notch_deg: f64, notch_top: f64) -> CutTooth {
    let cbct = ellipsoid(40, 48, 4.0, 10.0);
    let fine = ellipsoid(80, 96, 4.0, 10.0);
    let keep = |v: u32| {
        let p = fine.positions[v as usize];
        let at = p.y.atan2(p.x).to_degrees().abs();
        p.z > if at < notch_deg { notch_top } else { 4.0 }
    };
    let mut crown = TriMesh::new(
        fine.positions.clone(),
        fine.triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&v| keep(v)))
            .collect(),
    );
    crown.compact();
    let opts = FuseOptions::default();
    cut_tooth(11, &crown, &cbct, &Rigid::IDENTITY, &Rigid::IDENTITY, &opts)
        .expect("the ellipsoid tooth cuts")
}
