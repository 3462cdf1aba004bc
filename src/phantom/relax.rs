//! Tangential relaxation of a surface-nets mesh on its implicit surface: a scanner's mesh has
//! evenly spread vertices, while surface nets leave vertices close together wherever the surface
//! passes near a grid corner. Those slivers fold over under the smallest noise or projection,
//! which a real scan does not do.

use super::project::project;
use crate::mesh::{EdgeTopology, TriMesh};
use glam::DVec3;

/// Vertex moves that never fold the mesh: a move is made only if no incident face turns by more
/// than ~45°.
pub struct FoldGuard {
    faces_of: Vec<Vec<u32>>,
}

fn unit_normal(pos: &[DVec3], t: [u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| pos[v as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

impl FoldGuard {
    /// The guard of `mesh` (its faces must not change while the guard is used).
    pub fn new(mesh: &TriMesh) -> Self {
        let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                faces_of[v as usize].push(f as u32);
            }
        }
        FoldGuard { faces_of }
    }

    /// Moves vertex `v` to `q` unless that folds an incident face; returns whether it moved.
    pub fn try_move(&self, mesh: &mut TriMesh, v: usize, q: DVec3) -> bool {
        let faces = &self.faces_of[v];
        let before: Vec<DVec3> = faces
            .iter()
            .map(|&f| unit_normal(&mesh.positions, mesh.triangles[f as usize]))
            .collect();
        let p = mesh.positions[v];
        mesh.positions[v] = q;
        let folds = faces.iter().zip(&before).any(|(&f, nb)| {
            unit_normal(&mesh.positions, mesh.triangles[f as usize]).dot(*nb) < 0.7
        });
        if folds {
            mesh.positions[v] = p;
        }
        !folds
    }
}

/// Moves every vertex `iters` times half-way to the mean of its neighbours within its tangent
/// plane, then back onto the zero set of `f(v, ·)` (one damped Newton step of at most `max_step`),
/// through `guard`. Boundary vertices move only along the boundary (mean of their two boundary
/// neighbours). Only `movable` vertices move. Gauss-Seidel updates in vertex order: deterministic.
pub fn relax_on_surface(
    mesh: &mut TriMesh,
    guard: &FoldGuard,
    f: &impl Fn(usize, DVec3) -> f64,
    movable: &[bool],
    max_step: f64,
    iters: usize,
) {
    let n = mesh.positions.len();
    let topo = EdgeTopology::new(mesh);
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut boundary_nbrs: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (a, b, count) in topo.undirected_edges() {
        nbrs[a as usize].push(b);
        nbrs[b as usize].push(a);
        if count == 1 {
            boundary_nbrs[a as usize].push(b);
            boundary_nbrs[b as usize].push(a);
        }
    }
    for _ in 0..iters {
        let normals = mesh.vertex_normals();
        for v in (0..n).filter(|&v| movable[v]) {
            let (list, on_boundary) = if boundary_nbrs[v].is_empty() {
                (&nbrs[v], false)
            } else if boundary_nbrs[v].len() == 2 {
                (&boundary_nbrs[v], true)
            } else {
                continue; // a pinch: leave it
            };
            if list.is_empty() {
                continue;
            }
            let p = mesh.positions[v];
            let mean = list
                .iter()
                .map(|&w| mesh.positions[w as usize])
                .sum::<DVec3>()
                / list.len() as f64;
            let mut d = (mean - p) * 0.5;
            if !on_boundary {
                let nv = normals[v];
                d -= nv * nv.dot(d);
            }
            let fv = |q: DVec3| f(v, q);
            let q = project(p + d, &fv, max_step);
            guard.try_move(mesh, v, q);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::project::mesh_implicit;

    fn min_angle_deg(m: &TriMesh) -> f64 {
        let mut worst = 180.0f64;
        for t in &m.triangles {
            let p = t.map(|v| m.positions[v as usize]);
            for k in 0..3 {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                worst = worst.min(a.angle_between(b).to_degrees());
            }
        }
        worst
    }

    #[test]
    fn relaxation_keeps_the_surface_and_opens_slivers() {
        let c = DVec3::new(0.013, -0.021, 0.007);
        let f = |p: DVec3| (p - c).length() - 2.0;
        let mut m = mesh_implicit(DVec3::splat(-2.6), DVec3::splat(2.6), 0.18, f);
        let before = min_angle_deg(&m);
        let guard = FoldGuard::new(&m);
        let movable = vec![true; m.positions.len()];
        relax_on_surface(&mut m, &guard, &|_, p| f(p), &movable, 0.09, 3);
        let after = min_angle_deg(&m);
        for p in &m.positions {
            assert!(f(*p).abs() < 1e-3, "off the sphere by {}", f(*p));
        }
        assert!(
            after > before + 5.0,
            "min angle {before:.1}° -> {after:.1}°"
        );
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn the_guard_refuses_a_fold() {
        let mut m = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)],
            vec![[0, 1, 2], [1, 3, 2]],
        );
        let g = FoldGuard::new(&m);
        assert!(!g.try_move(&mut m, 3, DVec3::new(0.2, 0.2, 0.0)));
        assert_eq!(m.positions[3], DVec3::new(1.0, 1.0, 0.0));
        assert!(g.try_move(&mut m, 3, DVec3::new(1.1, 0.9, 0.05)));
    }
}
