//! Surface nets (Gibson 1998): one vertex per sign-changing cell at the mean of its edge
//! crossings, one quad (two triangles) per sign-changing grid edge. On a well-composed grid
//! whose outer layer is outside (see [`Grid`]) the result is a closed, oriented 2-manifold
//! with outward normals.

use super::grid::Grid;
use crate::mesh::{TriMesh, connected_components};
use glam::DVec3;

/// The 12 cell edges as pairs of corner indices (corner bit 0 = x, 1 = y, 2 = z).
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// Extracts the zero level set of `grid` (negative inside). Call
/// [`Grid::make_well_composed`] first for a manifold result. Returns the mesh (all components).
pub fn surface_nets(grid: &Grid) -> TriMesh {
    surface_nets_split(grid, false)
}

/// [`surface_nets`], or when `rough` the same topology with the slivers of a marching-cubes
/// export: each vertex moved 70 % of the way from the mean of its cell's edge crossings to the
/// crossing nearest a grid corner (where the surface passes near a corner, the cells around it
/// crowd their vertices there, as marching cubes' edge vertices do), and each quad split along
/// its longer diagonal.
pub fn surface_nets_split(grid: &Grid, rough: bool) -> TriMesh {
    let [nx, ny, nz] = grid.dims;
    let v = &grid.values;
    // Pass 1: vertices of sign-changing cells, in cell index order.
    let mut cells: Vec<usize> = Vec::new();
    let mut positions: Vec<DVec3> = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let ids: [usize; 8] = std::array::from_fn(|c| {
                    grid.idx(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))
                });
                let vals: [f32; 8] = std::array::from_fn(|c| v[ids[c]]);
                let n_in = vals.iter().filter(|&&x| x < 0.0).count();
                if n_in == 0 || n_in == 8 {
                    continue;
                }
                let mut sum = DVec3::ZERO;
                let mut cnt = 0.0;
                let mut near_corner = (f64::INFINITY, DVec3::ZERO);
                for &(a, b) in &EDGES {
                    let (va, vb) = (vals[a] as f64, vals[b] as f64);
                    if (va < 0.0) != (vb < 0.0) {
                        let t = (va / (va - vb)).clamp(0.0, 1.0);
                        let pa = corner(a);
                        let pb = corner(b);
                        sum += pa + (pb - pa) * t;
                        cnt += 1.0;
                        if t.min(1.0 - t) < near_corner.0 {
                            near_corner = (t.min(1.0 - t), pa + (pb - pa) * t);
                        }
                    }
                }
                let mut local = sum / cnt;
                if rough {
                    local += (near_corner.1 - local) * 0.7;
                }
                cells.push(grid.idx(i, j, k));
                positions.push(
                    grid.origin + (DVec3::new(i as f64, j as f64, k as f64) + local) * grid.h,
                );
            }
        }
    }
    let find = |i: usize, j: usize, k: usize| -> u32 {
        let id = grid.idx(i, j, k);
        cells
            .binary_search(&id)
            .map(|x| x as u32)
            .unwrap_or(u32::MAX)
    };
    // Pass 2: quads around sign-changing edges. Such an edge from sample s along an axis is an
    // edge of the cell whose low corner is s, and that cell is mixed: visit only mixed cells.
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(positions.len() * 2);
    for &cell in &cells {
        let i = cell % nx;
        let j = (cell / nx) % ny;
        let k = cell / (nx * ny);
        if i == 0 || j == 0 || k == 0 {
            continue; // edges on the outer layer never change sign
        }
        let s0 = v[cell] < 0.0;
        for axis in 0..3 {
            let (i1, j1, k1) = match axis {
                0 => (i + 1, j, k),
                1 => (i, j + 1, k),
                _ => (i, j, k + 1),
            };
            if i1 >= nx || j1 >= ny || k1 >= nz {
                continue;
            }
            let s1 = v[grid.idx(i1, j1, k1)] < 0.0;
            if s0 == s1 {
                continue;
            }
            // Cells around the edge, counter-clockwise seen from +axis (b, c cyclic).
            let around = |db: usize, dc: usize| -> (usize, usize, usize) {
                match axis {
                    0 => (i, j - 1 + db, k - 1 + dc),
                    1 => (i - 1 + dc, j, k - 1 + db),
                    _ => (i - 1 + db, j - 1 + dc, k),
                }
            };
            let ring = [around(0, 0), around(1, 0), around(1, 1), around(0, 1)];
            let mut q: [u32; 4] = std::array::from_fn(|n| find(ring[n].0, ring[n].1, ring[n].2));
            if q.contains(&u32::MAX) {
                continue; // cannot happen on a grid with an outside border
            }
            if !s0 {
                q.reverse();
            }
            let p: [DVec3; 4] = std::array::from_fn(|n| positions[q[n] as usize]);
            if ((p[0] - p[2]).length_squared() <= (p[1] - p[3]).length_squared()) != rough {
                tris.push([q[0], q[1], q[2]]);
                tris.push([q[0], q[2], q[3]]);
            } else {
                tris.push([q[0], q[1], q[3]]);
                tris.push([q[1], q[2], q[3]]);
            }
        }
    }
    TriMesh::new(positions, tris)
}

fn corner(c: usize) -> DVec3 {
    DVec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64)
}

/// Keeps the connected component with the most faces (ties: lowest component id) and drops
/// unused vertices.
pub fn largest_component(mesh: &TriMesh) -> TriMesh {
    let (ids, count) = connected_components(mesh);
    if count <= 1 {
        let mut m = mesh.clone();
        m.compact();
        return m;
    }
    let mut sizes = vec![0usize; count];
    for &c in &ids {
        sizes[c as usize] += 1;
    }
    let best = (0..count)
        .max_by_key(|&c| (sizes[c], usize::MAX - c))
        .unwrap_or(0) as u32;
    let tris = mesh
        .triangles
        .iter()
        .zip(&ids)
        .filter(|&(_, &c)| c == best)
        .map(|(t, _)| *t)
        .collect();
    let mut m = TriMesh::new(mesh.positions.clone(), tris);
    m.compact();
    m
}

/// Grid → well-composed → surface nets → largest component: a closed manifold mesh of the
/// region `values < 0`.
pub fn extract_closed(grid: &mut Grid) -> TriMesh {
    grid.make_well_composed();
    largest_component(&surface_nets(grid))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ValidateOptions;

    fn check_closed(m: &TriMesh) {
        let r = m
            .validate(&ValidateOptions {
                require_closed: true,
                allow_zero_area: false,
            })
            .expect("valid closed mesh");
        assert!(r.is_closed_manifold());
        assert_eq!(r.components, 1);
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn sphere_is_closed_with_right_volume() {
        let mut g = Grid::covering(DVec3::splat(-3.0), DVec3::splat(3.0), 0.2, 2);
        g.fill(4, 1.0, |p| p.length() - 2.5);
        let m = extract_closed(&mut g);
        check_closed(&m);
        let v = m.signed_volume();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 2.5f64.powi(3);
        assert!((v - exact).abs() / exact < 0.03, "volume {v} vs {exact}");
        for p in &m.positions {
            assert!((p.length() - 2.5).abs() < 0.05);
        }
    }

    #[test]
    fn ambiguous_field_becomes_manifold() {
        // Two spheres touching at one point and a thin noisy shell: many critical cells.
        let mut g = Grid::covering(DVec3::splat(-3.0), DVec3::splat(3.0), 0.25, 2);
        g.fill(1, 1.0, |p| {
            let a = (p - DVec3::new(-1.2, 0.0, 0.0)).length() - 1.2;
            let b = (p - DVec3::new(1.2, 0.0, 0.0)).length() - 1.2;
            let noise = ((p.x * 13.1).sin() * (p.y * 17.3).cos() * (p.z * 11.7).sin()) * 0.15;
            a.min(b) + noise
        });
        let flipped = g.make_well_composed();
        let m = surface_nets(&g);
        let r = m.validate(&ValidateOptions::default()).expect("valid");
        assert_eq!(r.boundary_edges, 0);
        assert_eq!(r.non_manifold_edges, 0, "flipped {flipped}");
        assert_eq!(r.non_manifold_vertices, 0);
        check_closed(&largest_component(&m));
    }
}
