//! Meshing an implicit region and projecting points onto an implicit surface.

use super::grid::Grid;
use super::surface_nets::extract_closed;
use crate::mesh::TriMesh;
use glam::DVec3;

/// Closed manifold mesh of `{f < 0}` inside the box `[lo, hi]` at spacing `h`.
pub fn mesh_implicit(lo: DVec3, hi: DVec3, h: f64, f: impl Fn(DVec3) -> f64 + Sync) -> TriMesh {
    let mut g = Grid::covering(lo, hi, h, 2);
    g.fill(16, 2.0, &f);
    extract_closed(&mut g)
}

/// Moves `p` (already within a fraction of a grid step) onto the zero set of `f` by one damped
/// Newton step (forward-difference gradient) of at most `max_step`; returns the input when the field is flat.
pub fn project(p: DVec3, f: &impl Fn(DVec3) -> f64, max_step: f64) -> DVec3 {
    let mut q = p;
    let e = 1e-5;
    for _ in 0..1 {
        let v = f(q);
        if v.abs() < 1e-7 {
            break;
        }
        let g = DVec3::new(
            f(q + DVec3::X * e) - v,
            f(q + DVec3::Y * e) - v,
            f(q + DVec3::Z * e) - v,
        ) / e;
        let g2 = g.length_squared();
        if g2 < 1e-12 {
            break;
        }
        let step = g * (v / g2);
        let len = step.length();
        q -= if len > max_step {
            step * (max_step / len)
        } else {
            step
        };
    }
    q
}
