//! Unsigned distance from points to a triangle surface (exact closest point on triangles,
//! grid-accelerated), for accuracy measurements against a ground-truth surface.

use super::grid::TriangleGrid;
use crate::mesh::TriMesh;
use glam::DVec3;

/// A surface prepared for repeated point-distance queries.
#[derive(Clone, Debug)]
pub struct SurfaceDistance {
    mesh: TriMesh,
    grid: TriangleGrid,
}

impl SurfaceDistance {
    /// Prepares `surface` (cloned) for queries.
    pub fn new(surface: &TriMesh) -> Self {
        Self {
            mesh: surface.clone(),
            grid: TriangleGrid::new(surface, 0.0),
        }
    }

    /// Distance from `p` to the surface (infinity for an empty surface).
    pub fn distance(&self, p: DVec3) -> f64 {
        self.grid
            .nearest(&self.mesh, p)
            .map_or(f64::INFINITY, |(d, _, _)| d)
    }

    /// Closest surface point to `p`, if the surface is not empty.
    pub fn closest_point(&self, p: DVec3) -> Option<DVec3> {
        self.grid.nearest(&self.mesh, p).map(|(_, _, q)| q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cube;

    #[test]
    fn distances_to_a_cube() {
        let s = SurfaceDistance::new(&cube(2.0));
        assert!((s.distance(DVec3::new(1.0, 1.0, 1.0)) - 1.0).abs() < 1e-12);
        assert!((s.distance(DVec3::new(5.0, 1.0, 1.0)) - 3.0).abs() < 1e-12);
        assert!((s.distance(DVec3::new(3.0, 3.0, 1.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert!(s.distance(DVec3::new(0.5, 0.0, 0.7)).abs() < 1e-12);
    }
}
