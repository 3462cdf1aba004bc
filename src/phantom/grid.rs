//! A regular scalar grid (negative inside), filled coarse-to-fine from an implicit function,
//! and repaired to be *well-composed* so that surface nets on it is a closed 2-manifold.
//!
//! Well-composed (Latecki 1997): no 2×2 face with a diagonal inside/outside pattern and no 2×2×2
//! cube whose inside (or outside) is two opposite corners only. Then inside and outside are each
//! face-connected in every cell, the sign changes on a cell's surface form one loop, and the
//! dual surface (one vertex per cell, one quad per sign-changing edge) is a 2-manifold.

use glam::DVec3;

/// A scalar field sampled on `dims` points spaced `h` from `origin` (x fastest).
#[derive(Clone, Debug)]
pub struct Grid {
    /// Position of sample (0,0,0).
    pub origin: DVec3,
    /// Spacing (mm).
    pub h: f64,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Values, x fastest; negative = inside.
    pub values: Vec<f32>,
}

impl Grid {
    /// A grid covering the box `[lo, hi]` padded by `pad` samples, all values outside (+h).
    pub fn covering(lo: DVec3, hi: DVec3, h: f64, pad: usize) -> Grid {
        let origin = lo - DVec3::splat(pad as f64 * h);
        let ext = hi - lo;
        let n = |e: f64| (e / h).ceil() as usize + 1 + 2 * pad;
        let dims = [n(ext.x), n(ext.y), n(ext.z)];
        Grid {
            origin,
            h,
            dims,
            values: vec![h as f32; dims[0] * dims[1] * dims[2]],
        }
    }

    /// Linear index of sample (i, j, k).
    #[inline]
    pub fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Position of sample (i, j, k).
    #[inline]
    pub fn point(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.h
    }

    /// Fills the grid from `f` (negative inside, |f(p) − f(q)| ≤ `lipschitz`·|p − q|),
    /// coarse-to-fine: a block whose 8 corner values share a sign and exceed `lipschitz` times
    /// its half-diagonal cannot contain the surface and is filled by trilinear interpolation of
    /// its corners (same sign, so the surface is unaffected); other blocks are split in 8, down
    /// to single cells. `block` is the top-level block size in samples (a power of two).
    /// Finally forces the outer layer of samples outside.
    pub fn fill(&mut self, block: usize, lipschitz: f64, f: impl Fn(DVec3) -> f64 + Sync) {
        super::grid_fill::fill(self, block, lipschitz, &f);
        self.force_border_outside();
    }

    /// Sets the outer layer of samples to a positive value, so the surface is closed.
    pub fn force_border_outside(&mut self) {
        let [nx, ny, nz] = self.dims;
        let hv = (0.5 * self.h) as f32;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    if i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1 {
                        let id = self.idx(i, j, k);
                        if self.values[id] <= 0.0 {
                            self.values[id] = hv;
                        }
                    }
                }
            }
        }
    }

    /// Makes the inside/outside classification well-composed by turning outside samples inside
    /// (monotone, so it terminates); returns how many samples were turned. Values exactly 0 are
    /// first nudged outside so that "inside" is strictly `v < 0`.
    pub fn make_well_composed(&mut self) -> usize {
        let tiny = (1e-6 * self.h) as f32;
        for v in &mut self.values {
            if *v == 0.0 {
                *v = tiny;
            }
        }
        let [nx, ny, nz] = self.dims;
        let mut flipped = 0;
        // Worklist of cells (by low-corner sample index): first every mixed cell, then the cells
        // around each turned sample.
        let mut work: Vec<usize> = Vec::new();
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let c = self.idx(i, j, k);
                    let v0 = self.values[c] < 0.0;
                    let mixed = (0..8).any(|q| {
                        (self.values[self.idx(i + (q & 1), j + ((q >> 1) & 1), k + (q >> 2))] < 0.0)
                            != v0
                    });
                    if mixed {
                        work.push(c);
                    }
                }
            }
        }
        while !work.is_empty() {
            work.sort_unstable();
            work.dedup();
            let mut next = Vec::new();
            for &cell in &work {
                let i = cell % nx;
                let j = (cell / nx) % ny;
                let k = cell / (nx * ny);
                if i + 1 >= nx || j + 1 >= ny || k + 1 >= nz {
                    continue;
                }
                if let Some(c) = self.critical_fix(i, j, k) {
                    let (ci, cj, ck) = (i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                    let id = self.idx(ci, cj, ck);
                    self.values[id] = -tiny;
                    flipped += 1;
                    for q in 0..8 {
                        let (di, dj, dk) = (q & 1, (q >> 1) & 1, q >> 2);
                        if ci >= di && cj >= dj && ck >= dk {
                            next.push(self.idx(ci - di, cj - dj, ck - dk));
                        }
                    }
                    next.push(cell);
                }
            }
            work = next;
        }
        flipped
    }

    /// The corner (bit 0 = x, 1 = y, 2 = z) of cell (i, j, k) to turn inside to remove a
    /// critical configuration of the cell, if it has one.
    fn critical_fix(&self, i: usize, j: usize, k: usize) -> Option<usize> {
        let [nx, ny, nz] = self.dims;
        let ids: [usize; 8] =
            std::array::from_fn(|c| self.idx(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)));
        let ins: [bool; 8] = std::array::from_fn(|c| self.values[ids[c]] < 0.0);
        let n_in = ins.iter().filter(|&&b| b).count();
        if n_in == 0 || n_in == 8 {
            return None;
        }
        // All six faces of the cell (each face is shared, checking twice is harmless).
        const FACES: [[usize; 4]; 6] = [
            [0, 1, 3, 2],
            [0, 1, 5, 4],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
            [2, 3, 7, 6],
            [4, 5, 7, 6],
        ];
        for q in FACES {
            let (a, b, c, d) = (ins[q[0]], ins[q[1]], ins[q[2]], ins[q[3]]);
            if a == c && b == d && a != b {
                let (o1, o2) = if a { (q[1], q[3]) } else { (q[0], q[2]) };
                return Some(if self.values[ids[o1]] <= self.values[ids[o2]] {
                    o1
                } else {
                    o2
                });
            }
        }
        if n_in == 2 || n_in == 6 {
            for c in 0..4 {
                let o = 7 - c;
                if n_in == 6 && !ins[c] && !ins[o] {
                    return Some(c);
                }
                if n_in == 2 && ins[c] && ins[o] {
                    let on_border = |x: usize| {
                        let (ii, jj, kk) = (i + (x & 1), j + ((x >> 1) & 1), k + (x >> 2));
                        ii == 0
                            || jj == 0
                            || kk == 0
                            || ii == nx - 1
                            || jj == ny - 1
                            || kk == nz - 1
                    };
                    return [c ^ 1, c ^ 2, c ^ 4]
                        .into_iter()
                        .filter(|&x| !on_border(x))
                        .min_by(|&x, &y| self.values[ids[x]].total_cmp(&self.values[ids[y]]));
                }
            }
        }
        None
    }
}

pub(super) fn trilinear(c: &[f64; 8], tx: f64, ty: f64, tz: f64) -> f64 {
    let l = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let x00 = l(c[0], c[1], tx);
    let x10 = l(c[2], c[3], tx);
    let x01 = l(c[4], c[5], tx);
    let x11 = l(c[6], c[7], tx);
    l(l(x00, x10, ty), l(x01, x11, ty), tz)
}
