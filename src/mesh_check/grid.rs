//! A uniform grid of triangle bounding boxes: candidate pairs for intersection tests and
//! ring-by-ring nearest-triangle search. Deterministic (sorted vectors, no hashing).

use crate::geom::{closest_point_on_triangle, floor_i64};
use crate::mesh::TriMesh;
use glam::DVec3;

/// Triangles binned by the grid cells their bounding boxes overlap.
#[derive(Clone, Debug)]
pub struct TriangleGrid {
    /// Lower corner of the grid.
    pub origin: DVec3,
    /// Cell edge length (mm).
    pub cell: f64,
    /// Cells along x, y, z.
    pub dims: [i64; 3],
    /// `cell id << face_bits | face`, sorted (so by cell, then by face).
    entries: Vec<u64>,
    /// Bits the face index takes in an entry.
    face_bits: u32,
    /// One bit per cell: whether any face is binned there (lets a query skip empty cells
    /// without a search).
    occupied: Vec<u64>,
}

impl TriangleGrid {
    /// Builds the grid over `mesh`; `cell <= 0` picks a cell about twice the mean edge length
    /// (bounded so the grid has at most ~4 million cells).
    pub fn new(mesh: &TriMesh, cell: f64) -> Self {
        let all: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
        Self::over(mesh, &all, cell)
    }

    /// Like [`TriangleGrid::new`], over the faces `faces` of `mesh` only (the grid spans all
    /// of `mesh`'s vertices).
    pub fn over(mesh: &TriMesh, faces: &[u32], cell: f64) -> Self {
        let region =
            crate::geom::bounding_box(&mesh.positions).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        Self::over_region(mesh, faces, region, cell)
    }

    /// Like [`TriangleGrid::over`], with the grid spanning the box `region` only (faces reaching
    /// outside it are binned in its border cells; queries outside it clamp to them too).
    pub fn over_region(mesh: &TriMesh, faces: &[u32], region: (DVec3, DVec3), cell: f64) -> Self {
        let (lo, hi) = region;
        let ext = (hi - lo).max(DVec3::splat(1e-9));
        let mut cell = if cell > 0.0 {
            cell
        } else {
            2.0 * mesh.mean_edge_length()
        };
        let min_cell = (ext.x * ext.y * ext.z / 4.0e6).cbrt();
        if !(cell.is_finite() && cell > min_cell) {
            cell = min_cell.max(1e-6);
        }
        let dims = [
            (ext.x / cell).floor() as i64 + 1,
            (ext.y / cell).floor() as i64 + 1,
            (ext.z / cell).floor() as i64 + 1,
        ];
        let max_face = faces.iter().copied().max().unwrap_or(0);
        let mut g = Self {
            origin: lo,
            cell,
            dims,
            entries: Vec::new(),
            face_bits: u32::BITS - max_face.leading_zeros(),
            occupied: vec![0; ((dims[0] * dims[1] * dims[2]) as usize).div_ceil(64)],
        };
        for &f in faces {
            let [a, b, c] = mesh.corners(f as usize);
            let (l, h) = (a.min(b).min(c), a.max(b).max(c));
            let (il, ih) = (g.index_of(l), g.index_of(h));
            for z in il[2]..=ih[2] {
                for y in il[1]..=ih[1] {
                    for x in il[0]..=ih[0] {
                        let id = g.id([x, y, z]);
                        g.occupied[(id / 64) as usize] |= 1 << (id % 64);
                        g.entries.push(id << g.face_bits | f as u64);
                    }
                }
            }
        }
        // Entries are pushed face by face: for faces in increasing order they are sorted by
        // face already, and a stable sort by cell alone gives the order by (cell, face).
        if faces.windows(2).all(|w| w[0] < w[1]) {
            let bits = g.face_bits;
            crate::radix::sort_by_key(&mut g.entries, |&k| k >> bits);
        } else {
            crate::radix::sort_by_key(&mut g.entries, |&k| k);
        }
        g
    }

    fn cell_of_entry(&self, e: u64) -> u64 {
        e >> self.face_bits
    }

    fn face_of_entry(&self, e: u64) -> u32 {
        (e & ((1u64 << self.face_bits) - 1)) as u32
    }

    fn index_unclamped(&self, p: DVec3) -> [i64; 3] {
        let q = (p - self.origin) / self.cell;
        [floor_i64(q.x), floor_i64(q.y), floor_i64(q.z)]
    }

    fn index_of(&self, p: DVec3) -> [i64; 3] {
        let i = self.index_unclamped(p);
        [0, 1, 2].map(|k| i[k].clamp(0, self.dims[k] - 1))
    }

    fn id(&self, i: [i64; 3]) -> u64 {
        ((i[2] * self.dims[1] + i[1]) * self.dims[0] + i[0]) as u64
    }

    fn faces_in(&self, id: u64) -> impl Iterator<Item = u32> + '_ {
        let s = self
            .entries
            .partition_point(|&e| self.cell_of_entry(e) < id);
        self.entries[s..]
            .iter()
            .take_while(move |&&e| self.cell_of_entry(e) == id)
            .map(|&e| self.face_of_entry(e))
    }

    /// The binned faces sharing a cell with the box `[lo, hi]`, sorted and unique (a superset
    /// of the faces whose bounding boxes overlap it).
    pub fn faces_in_box(&self, lo: DVec3, hi: DVec3) -> Vec<u32> {
        let mut out = Vec::new();
        self.for_each_in_box(lo, hi, |f| out.push(f));
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Calls `visit` for every binned face in each cell the box `[lo, hi]` meets (a face in
    /// several of those cells is visited once per cell); empty cells cost no search.
    pub fn for_each_in_box(&self, lo: DVec3, hi: DVec3, mut visit: impl FnMut(u32)) {
        let (il, ih) = (self.index_of(lo), self.index_of(hi));
        for z in il[2]..=ih[2] {
            for y in il[1]..=ih[1] {
                for x in il[0]..=ih[0] {
                    let id = self.id([x, y, z]);
                    if self.occupied[(id / 64) as usize] & (1 << (id % 64)) != 0 {
                        self.faces_in(id).for_each(&mut visit);
                    }
                }
            }
        }
    }

    /// Face pairs `(f, g)`, `f < g`, sharing at least one cell and with overlapping bounding
    /// boxes; sorted and unique. Each pair is taken in one cell only: the cell of the lowest
    /// corner of the two boxes' overlap, which both faces are binned in (the cell index of a
    /// coordinate never decreases as the coordinate grows), so no pair is found twice.
    pub fn candidate_pairs(&self, mesh: &TriMesh) -> Vec<(u32, u32)> {
        let mut keys = self.candidate_keys(mesh);
        crate::radix::sort_by_key(&mut keys, |&k| k);
        keys.dedup();
        keys.into_iter()
            .map(|k| ((k >> self.face_bits) as u32, self.face_of_entry(k)))
            .collect()
    }

    /// The pairs of [`TriangleGrid::candidate_pairs`] in no particular order, for callers that
    /// test each pair or count them and do not need the order. Unique when the grid was built
    /// over distinct faces (each pair is taken in one cell only).
    pub fn candidate_pairs_unordered(&self, mesh: &TriMesh) -> Vec<(u32, u32)> {
        self.candidate_keys(mesh)
            .into_iter()
            .map(|k| ((k >> self.face_bits) as u32, self.face_of_entry(k)))
            .collect()
    }

    /// The pairs of [`TriangleGrid::candidate_pairs`] as keys `f << face_bits | g`, in the
    /// order the cells are visited.
    fn candidate_keys(&self, mesh: &TriMesh) -> Vec<u64> {
        let bbox = |f: u32| {
            let [a, b, c] = mesh.corners(f as usize);
            (a.min(b).min(c), a.max(b).max(c))
        };
        let mut keys: Vec<u64> = Vec::new();
        // One cell's faces: each with its box and the cell of its box's lower corner.
        let mut run: Vec<(u32, (DVec3, DVec3), [i64; 3])> = Vec::new();
        let mut i = 0;
        while i < self.entries.len() {
            let id = self.cell_of_entry(self.entries[i]);
            run.clear();
            while i < self.entries.len() && self.cell_of_entry(self.entries[i]) == id {
                let f = self.face_of_entry(self.entries[i]);
                let b = bbox(f);
                run.push((f, b, self.index_of(b.0)));
                i += 1;
            }
            let at = self.coords(id);
            for (k, &(f, (fl, fh), fi)) in run.iter().enumerate() {
                for &(g, (gl, gh), gi) in &run[k + 1..] {
                    if fl.cmple(gh).all()
                        && gl.cmple(fh).all()
                        && (0..3).all(|a| fi[a].max(gi[a]) == at[a])
                    {
                        let (lo, hi) = (f.min(g) as u64, f.max(g) as u64);
                        keys.push(lo << self.face_bits | hi);
                    }
                }
            }
        }
        keys
    }

    /// The cell coordinates of cell `id`.
    fn coords(&self, id: u64) -> [i64; 3] {
        let id = id as i64;
        let (x, yz) = (id % self.dims[0], id / self.dims[0]);
        [x, yz % self.dims[1], yz / self.dims[1]]
    }

    /// The nearest point of the mesh surface to `p`: `(distance, face, closest point)`, or
    /// `None` for an empty mesh.
    pub fn nearest(&self, mesh: &TriMesh, p: DVec3) -> Option<(f64, u32, DVec3)> {
        if self.entries.is_empty() {
            return None;
        }
        let c = self.index_unclamped(p);
        let mut best: Option<(f64, u32, DVec3)> = None;
        let max_r = (0..3)
            .map(|k| (c[k]).abs().max((c[k] - self.dims[k]).abs()))
            .max()
            .unwrap_or(0)
            + 1;
        for r in 0..=max_r {
            for z in c[2] - r..=c[2] + r {
                if z < 0 || z >= self.dims[2] {
                    continue;
                }
                for y in c[1] - r..=c[1] + r {
                    if y < 0 || y >= self.dims[1] {
                        continue;
                    }
                    for x in c[0] - r..=c[0] + r {
                        if x < 0 || x >= self.dims[0] {
                            continue;
                        }
                        let on_ring =
                            (x - c[0]).abs() == r || (y - c[1]).abs() == r || (z - c[2]).abs() == r;
                        if !on_ring {
                            continue;
                        }
                        for f in self.faces_in(self.id([x, y, z])) {
                            let [a, b, cc] = mesh.corners(f as usize);
                            let q = closest_point_on_triangle(p, a, b, cc);
                            let d = (q - p).length();
                            if best.is_none_or(|(bd, bf, _)| d < bd || (d == bd && f < bf)) {
                                best = Some((d, f, q));
                            }
                        }
                    }
                }
            }
            if let Some((d, _, _)) = best
                && d <= r as f64 * self.cell
            {
                break;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of small triangles: the faces a box query visits are a superset of those whose
    /// boxes overlap it, for a grid over the whole mesh and over a sub-region alike, and the
    /// region grid's pairs are exactly the overlapping pairs among its faces.
    #[test]
    fn region_grid_queries_find_every_overlapping_face() {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..40 {
            let x = i as f64 * 0.1;
            let z = (i as f64 * 0.7).sin() * 0.05;
            positions.push(DVec3::new(x, 0.0, z));
            positions.push(DVec3::new(x + 0.05, 0.12, -z));
            if i > 0 {
                let (a, b, c, d) = (2 * i - 2, 2 * i - 1, 2 * i, 2 * i + 1);
                triangles.push([a as u32, c as u32, b as u32]);
                triangles.push([b as u32, c as u32, d as u32]);
            }
        }
        let mesh = TriMesh::new(positions, triangles);
        let bb = |f: usize| {
            let [a, b, c] = mesh.corners(f);
            (a.min(b).min(c), a.max(b).max(c))
        };
        let ov =
            |p: (DVec3, DVec3), q: (DVec3, DVec3)| p.0.cmple(q.1).all() && q.0.cmple(p.1).all();
        let sub: Vec<u32> = (20..50).collect();
        let region = (DVec3::new(0.9, -0.1, -0.1), DVec3::new(2.6, 0.3, 0.1));
        let g = TriangleGrid::over_region(&mesh, &sub, region, 0.07);
        for q in 0..mesh.triangles.len() {
            let mut seen = Vec::new();
            let (lo, hi) = bb(q);
            g.for_each_in_box(lo, hi, |f| seen.push(f));
            for &f in &sub {
                if ov(bb(f as usize), (lo, hi)) {
                    assert!(seen.contains(&f), "query {q}: face {f} missed");
                }
            }
        }
        let mut want = Vec::new();
        for (i, &f) in sub.iter().enumerate() {
            for &h in &sub[i + 1..] {
                if ov(bb(f as usize), bb(h as usize)) {
                    want.push((f, h));
                }
            }
        }
        assert!(!want.is_empty());
        assert_eq!(g.candidate_pairs(&mesh), want);
        // The same pairs unordered, each once.
        let mut unordered = g.candidate_pairs_unordered(&mesh);
        unordered.sort_unstable();
        assert_eq!(unordered, want);
    }
}
