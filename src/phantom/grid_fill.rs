//! Filling a [`Grid`] from an implicit function, coarse-to-fine, with the top-level blocks run in
//! parallel and the result bit for bit that of filling them one after another.
//!
//! The blocks are visited in order k, then j, then i; a block reads and writes only the samples
//! of its closed box, which it shares with its 26 neighbours (an interpolated sample written by
//! one block is read, not re-evaluated, by the next). With `w = i + 2j + 4k` (block indices), every
//! neighbour visited earlier has a smaller `w` and every neighbour visited later a larger one,
//! and two blocks of equal `w` share no sample. So the blocks of one `w` (a wave) run in
//! parallel once the waves before it are done, and each block sees its samples exactly as the
//! sequential visit would.

use super::grid::{Grid, trilinear};
use glam::DVec3;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The samples while they are filled (f32 bits; NaN = not set yet).
struct Filling<'a, F> {
    dims: [usize; 3],
    origin: DVec3,
    h: f64,
    values: Vec<AtomicU32>,
    f: &'a F,
    lipschitz: f64,
}

impl<F: Fn(DVec3) -> f64 + Sync> Filling<'_, F> {
    fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    fn get(&self, id: usize) -> f32 {
        f32::from_bits(self.values[id].load(Relaxed))
    }

    fn set(&self, id: usize, v: f32) {
        self.values[id].store(v.to_bits(), Relaxed);
    }

    fn value_at(&self, i: usize, j: usize, k: usize) -> f64 {
        let id = self.idx(i, j, k);
        let v = self.get(id);
        if v.is_nan() {
            let p = self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.h;
            let nv = (self.f)(p);
            self.set(id, nv as f32);
            nv
        } else {
            v as f64
        }
    }

    /// Fills the samples of the box `[lo, hi]`: by trilinear interpolation of its corners when
    /// they share a sign and exceed the Lipschitz bound over its half-diagonal (the surface cannot
    /// pass through it), else by splitting it in 8, down to single cells.
    fn block(&self, lo: [usize; 3], hi: [usize; 3]) {
        let corners: [f64; 8] = std::array::from_fn(|c| {
            let i = if c & 1 == 0 { lo[0] } else { hi[0] };
            let j = if c & 2 == 0 { lo[1] } else { hi[1] };
            let k = if c & 4 == 0 { lo[2] } else { hi[2] };
            self.value_at(i, j, k)
        });
        let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        if ext.iter().all(|&e| e <= 1) {
            return;
        }
        let half_diag =
            0.5 * self.h * ((ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]) as f64).sqrt();
        let same = corners.iter().all(|&v| v > 0.0) || corners.iter().all(|&v| v < 0.0);
        if same && corners.iter().all(|v| v.abs() > self.lipschitz * half_diag) {
            self.interpolate(lo, hi, ext, &corners);
            return;
        }
        let split = |a: usize| -> ([(usize, usize); 2], usize) {
            let (l, h) = (lo[a], hi[a]);
            if h - l >= 2 {
                let m = (l + h) / 2;
                ([(l, m), (m, h)], 2)
            } else {
                ([(l, h), (l, h)], 1)
            }
        };
        let (sx, sy, sz) = (split(0), split(1), split(2));
        for &(z0, z1) in &sz.0[..sz.1] {
            for &(y0, y1) in &sy.0[..sy.1] {
                for &(x0, x1) in &sx.0[..sx.1] {
                    self.block([x0, y0, z0], [x1, y1, z1]);
                }
            }
        }
    }

    fn interpolate(&self, lo: [usize; 3], hi: [usize; 3], ext: [usize; 3], corners: &[f64; 8]) {
        for k in lo[2]..=hi[2] {
            let tz = (k - lo[2]) as f64 / ext[2].max(1) as f64;
            for j in lo[1]..=hi[1] {
                let ty = (j - lo[1]) as f64 / ext[1].max(1) as f64;
                for i in lo[0]..=hi[0] {
                    let id = self.idx(i, j, k);
                    if self.get(id).is_nan() {
                        let tx = (i - lo[0]) as f64 / ext[0].max(1) as f64;
                        self.set(id, trilinear(corners, tx, ty, tz) as f32);
                    }
                }
            }
        }
    }
}

/// Fills every sample of `g` from `f` (see [`Grid::fill`]); samples no block reached get `g.h`.
pub(super) fn fill(g: &mut Grid, block: usize, lipschitz: f64, f: &(impl Fn(DVec3) -> f64 + Sync)) {
    let dims = g.dims;
    let nan = f32::NAN.to_bits();
    let filling = Filling {
        dims,
        origin: g.origin,
        h: g.h,
        values: (0..g.values.len()).map(|_| AtomicU32::new(nan)).collect(),
        f,
        lipschitz,
    };
    let b = block.max(1);
    // Blocks start at 0, b, 2b, … while start + 1 < n.
    let nb = dims.map(|n| n.saturating_sub(1).div_ceil(b));
    if nb.iter().all(|&n| n > 0) {
        let last_wave = (nb[0] - 1) + 2 * (nb[1] - 1) + 4 * (nb[2] - 1);
        for w in 0..=last_wave {
            let mut wave = Vec::new();
            for bk in 0..nb[2].min(w / 4 + 1) {
                for bj in 0..nb[1] {
                    let Some(bi) = w.checked_sub(2 * bj + 4 * bk) else {
                        break;
                    };
                    if bi < nb[0] {
                        wave.push([bi * b, bj * b, bk * b]);
                    }
                }
            }
            crate::par::map_ordered(&wave, |&lo| {
                let hi = [0, 1, 2].map(|a| (lo[a] + b).min(dims[a] - 1));
                filling.block(lo, hi);
            });
        }
    }
    for (out, v) in g.values.iter_mut().zip(filling.values) {
        let v = f32::from_bits(v.into_inner());
        *out = if v.is_nan() { g.h as f32 } else { v };
    }
}
