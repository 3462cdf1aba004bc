//! A tooth's vertices bucketed in a dense grid of cubes, for marking every vertex within a
//! small radius of many query points (the registration gate's crown-near CBCT vertices): each
//! query visits the few cubes its ball overlaps and tests their vertices, stored side by side,
//! instead of collecting a k-d tree search's answers one by one.

use glam::DVec3;

/// Edge length (mm) of the cubes, unless the mesh is too large for [`MAX_CELLS_PER_AXIS`].
const CELL_MM: f64 = 1.0;
/// Most cubes along one axis: a mesh far larger than a tooth (another unit, a whole scene) gets
/// larger cubes instead of a grid that does not fit in memory.
const MAX_CELLS_PER_AXIS: f64 = 128.0;

/// Vertices sorted by the cube that holds them.
pub(crate) struct VertexGrid {
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Per cube (x fastest), the start of its vertices in `ids` / `pos`; one more at the end.
    start: Vec<u32>,
    ids: Vec<u32>,
    pos: Vec<DVec3>,
}

impl VertexGrid {
    /// Buckets `positions` (finite). An empty slice gives an empty grid.
    pub(crate) fn new(positions: &[DVec3]) -> VertexGrid {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for p in positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if positions.is_empty() {
            (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
        }
        let cell = CELL_MM.max((hi - lo).max_element() / MAX_CELLS_PER_AXIS);
        let dims = ((hi - lo) / cell)
            .floor()
            .to_array()
            .map(|d| d as usize + 1);
        let mut grid = VertexGrid {
            origin: lo,
            cell,
            dims,
            start: Vec::new(),
            ids: Vec::new(),
            pos: Vec::new(),
        };
        let cube: Vec<usize> = positions
            .iter()
            .map(|p| grid.cube_of(grid.axis_cells(*p)))
            .collect();
        let mut count = vec![0u32; dims[0] * dims[1] * dims[2] + 1];
        for &c in &cube {
            count[c + 1] += 1;
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        grid.ids = vec![0; positions.len()];
        grid.pos = vec![DVec3::ZERO; positions.len()];
        for (v, (&c, p)) in cube.iter().zip(positions).enumerate() {
            let k = fill[c] as usize;
            grid.ids[k] = v as u32;
            grid.pos[k] = *p;
            fill[c] += 1;
        }
        grid.start = count;
        grid
    }

    /// The cube coordinates of `p`, clamped to the grid. Monotone in each coordinate (a
    /// subtraction and a division by a positive number, each rounded, then `floor`).
    fn axis_cells(&self, p: DVec3) -> [usize; 3] {
        let c = ((p - self.origin) / self.cell).floor();
        [0, 1, 2].map(|k| (c[k].max(0.0) as usize).min(self.dims[k] - 1))
    }

    fn cube_of(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Sets `near[v]` for every vertex `v` with `(q - v)·(q - v) < r2` exactly as glam computes
    /// it; `near` is indexed like the positions the grid was built from.
    pub(crate) fn mark_within(&self, q: DVec3, r2: f64, near: &mut [bool]) {
        if r2.is_nan() || r2 <= 0.0 || self.pos.is_empty() {
            return;
        }
        // Such a vertex differs from `q` by less than √r2 (rounded) along each axis; the box is
        // widened by a relative 1e-9 over that rounding, and the cube coordinates are monotone,
        // so every such vertex lies in a cube of the range.
        let r = r2.sqrt() * (1.0 + 1e-9);
        let (a, b) = (self.axis_cells(q - r), self.axis_cells(q + r));
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                let row = self.cube_of([0, y, z]);
                let (s, e) = (
                    self.start[row + a[0]] as usize,
                    self.start[row + b[0] + 1] as usize,
                );
                for (p, &v) in self.pos[s..e].iter().zip(&self.ids[s..e]) {
                    if q.distance_squared(*p) < r2 {
                        near[v as usize] = true;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter of points (a linear congruential generator), some of them
    /// exactly on cube faces.
    fn scatter(n: usize, scale: f64) -> Vec<DVec3> {
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|i| {
                let p = DVec3::new(next(), next(), next()) * scale;
                if i % 7 == 0 { p.round() } else { p }
            })
            .collect()
    }

    /// The grid marks exactly the vertices a test of every vertex marks, for radii below, at
    /// and above the cube size, query points inside and outside the vertices' box, and points
    /// at integer (cube-face) coordinates.
    #[test]
    fn marks_exactly_the_vertices_a_full_scan_marks() {
        for (n, scale) in [
            (0usize, 1.0),
            (1, 1.0),
            (500, 6.0),
            (3000, 12.0),
            (400, 900.0),
        ] {
            let pos = scatter(n, scale);
            let grid = VertexGrid::new(&pos);
            let queries: Vec<DVec3> = scatter(60, scale * 1.4)
                .into_iter()
                .map(|q| q - DVec3::splat(scale * 0.2))
                .chain(pos.iter().take(20).copied())
                .collect();
            for r2 in [0.0, 0.25, 1.0, 4.0, 9.0, 1e4] {
                let mut got = vec![false; pos.len()];
                for q in &queries {
                    grid.mark_within(*q, r2, &mut got);
                }
                let want: Vec<bool> = pos
                    .iter()
                    .map(|p| queries.iter().any(|q| q.distance_squared(*p) < r2))
                    .collect();
                assert_eq!(got, want, "n {n}, scale {scale}, r2 {r2}");
            }
        }
    }

    /// A mesh far larger than a tooth gets larger cubes, not a grid of billions.
    #[test]
    fn a_huge_extent_keeps_the_grid_small() {
        let pos = vec![DVec3::ZERO, DVec3::new(1e6, 2e6, 3e6)];
        let grid = VertexGrid::new(&pos);
        assert!(
            grid.dims
                .iter()
                .all(|&d| d <= MAX_CELLS_PER_AXIS as usize + 1)
        );
        let mut near = vec![false; 2];
        grid.mark_within(DVec3::new(1e6, 2e6, 3e6 - 1.0), 4.0, &mut near);
        assert_eq!(near, [false, true]);
    }
}
