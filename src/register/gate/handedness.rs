//! The handedness of the IOS crowns from their own geometry and FDI numbers, independent of the
//! CBCT: tells which modality a mirrored pair has reflected.

use super::mean;
use crate::arch::{arch_position, jaw_of};
use crate::register::ToothData;
use glam::DVec3;
use std::collections::BTreeMap;

/// The handedness of the IOS crowns from their own geometry: the occlusal direction (from each
/// crown's margin to its centroid), the patient's right-to-left direction (FDI sides) and the
/// front-to-back direction (incisors and canines vs premolars and molars) form a right- or
/// left-handed frame, fixed by anatomy for each jaw. `None` without teeth on both sides and both
/// in front and behind, or without margins.
pub(crate) fn ios_handedness(teeth: &BTreeMap<u8, ToothData>) -> Option<bool> {
    let mut up = DVec3::ZERO;
    let (mut right, mut left, mut front, mut back) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (&f, d) in teeth {
        up += d.ios_occlusal?;
        let c = d.ios_centroid;
        if arch_position(f) < 0 {
            right.push(c)
        } else {
            left.push(c)
        }
        if f % 10 <= 3 {
            front.push(c)
        } else {
            back.push(c)
        }
    }
    if [&right, &left, &front, &back].iter().any(|v| v.is_empty()) || up == DVec3::ZERO {
        return None;
    }
    let r = mean(&right) - mean(&left);
    let fwd = mean(&front) - mean(&back);
    let s = r.cross(fwd).dot(up.normalize());
    let upper = teeth
        .keys()
        .next()
        .is_some_and(|&f| jaw_of(f) == crate::arch::Jaw::Upper);
    Some((s > 0.0) == upper)
}

/// The occlusal direction of the IOS crown `mesh` whose centroid is `centroid` (unit, IOS
/// frame): from the centroid of its margin (its longest boundary loop) to its centroid. `None`
/// for a closed crown.
pub(crate) fn occlusal_of(mesh: &crate::mesh::TriMesh, centroid: DVec3) -> Option<DVec3> {
    let loops = crate::mesh::boundary_loops(mesh);
    let rim = loops.iter().max_by_key(|l| l.len())?;
    let b = mean(
        &rim.iter()
            .map(|&v| mesh.positions[v as usize])
            .collect::<Vec<_>>(),
    );
    Some((centroid - b).normalize_or_zero())
}
