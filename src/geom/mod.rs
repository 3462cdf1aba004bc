//! Small geometric primitives shared by every stage: rigid transforms, points, boxes.

mod rigid;
mod triangle;

pub use glam::{DMat3, DVec3};
pub use rigid::Rigid;
pub use triangle::closest_point_on_triangle;

/// Axis-aligned bounding box of a point set; `None` when empty.
pub fn bounding_box(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
    )
}

/// Mean of a point set; `None` when empty.
pub fn centroid(points: &[DVec3]) -> Option<DVec3> {
    if points.is_empty() {
        return None;
    }
    let sum = points.iter().fold(DVec3::ZERO, |acc, p| acc + *p);
    Some(sum / points.len() as f64)
}
