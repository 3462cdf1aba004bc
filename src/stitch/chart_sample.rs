//! Graded, deterministic Poisson-disk sampling of the band region in the chart (see
//! [`super::chart`]): spacing from the margin's edge length at the top to the cut's at the
//! bottom, points kept clear of loop vertices and edges so no sliver forms against a loop.

use super::chart::wrap;
use crate::geom::{ceil_i64, floor_i64};

/// Options of the chart sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleOptions {
    /// Edge length at the margin (mm).
    pub e_upper: f64,
    /// Edge length at the cut (mm).
    pub e_lower: f64,
    /// Poisson-disk radius as a fraction of the local edge length.
    pub radius: f64,
    /// Smallest distance from a loop edge as a fraction of the local edge length.
    pub clearance: f64,
}

/// Uniform grid over the periodic strip `[0, period) × [y0, y1]`.
struct Grid {
    period: f64,
    cw: f64,
    nx: usize,
    y0: f64,
    ch: f64,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(period: f64, y0: f64, y1: f64, cell: f64) -> Grid {
        let nx = ((period / cell).floor() as usize).max(1);
        let ny = (((y1 - y0) / cell).ceil() as usize).max(1) + 2;
        Grid {
            period,
            cw: period / nx as f64,
            nx,
            y0: y0 - cell,
            ch: cell,
            ny,
            cells: vec![Vec::new(); nx * ny],
        }
    }

    fn cell_of(&self, p: [f64; 2]) -> (i64, i64) {
        (
            floor_i64(p[0].rem_euclid(self.period) / self.cw),
            floor_i64((p[1] - self.y0) / self.ch),
        )
    }

    fn index(&self, cx: i64, cy: i64) -> Option<usize> {
        if cy < 0 || cy >= self.ny as i64 {
            return None;
        }
        Some(cy as usize * self.nx + cx.rem_euclid(self.nx as i64) as usize)
    }

    /// Inserts `id` into every cell overlapping the box of `a`–`b` (`b` unwrapped near `a`).
    fn insert_box(&mut self, id: u32, a: [f64; 2], b: [f64; 2]) {
        let fx = |x: f64| floor_i64(x / self.cw);
        let fy = |y: f64| floor_i64((y - self.y0) / self.ch);
        let (x0, x1) = (fx(a[0].min(b[0])), fx(a[0].max(b[0])));
        let (y0, y1) = (fy(a[1].min(b[1])), fy(a[1].max(b[1])));
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                if let Some(i) = self.index(cx, cy)
                    && self.cells[i].last() != Some(&id)
                {
                    self.cells[i].push(id);
                }
            }
        }
    }

    /// Whether `f` holds for every id in the 3×3 cells around `p` (ids may repeat). The answer
    /// does not depend on the order, so the likeliest failures are tried first: `p`'s own cell,
    /// and in each cell the ids inserted last (the sample grows outward from the margin, so the
    /// newest points are the nearest).
    fn near(&self, p: [f64; 2], mut f: impl FnMut(u32) -> bool) -> bool {
        const ORDER: [(i64, i64); 9] = [
            (0, 0),
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
            (1, 1),
        ];
        let (cx, cy) = self.cell_of(p);
        ORDER.iter().all(|&(dx, dy)| {
            self.index(cx + dx, cy + dy)
                .is_none_or(|i| self.cells[i].iter().rev().all(|&id| f(id)))
        })
    }
}

/// Squared distance from `p` to segment `a`–`b` in the periodic strip.
fn seg_dist2(p: [f64; 2], a: [f64; 2], b: [f64; 2], period: f64) -> f64 {
    let ax = p[0] + wrap(a[0] - p[0], period);
    let bx = ax + wrap(b[0] - a[0], period);
    let (ex, ey) = (bx - ax, b[1] - a[1]);
    let l2 = ex * ex + ey * ey;
    let t = if l2 > 0.0 {
        (((p[0] - ax) * ex + (p[1] - a[1]) * ey) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (ax + t * ex - p[0], a[1] + t * ey - p[1]);
    dx * dx + dy * dy
}

/// One run of a lattice column: the candidates between a loop crossing above and the next one
/// below, consecutive rows with consecutive creation indices. Its candidates' positions and
/// sizes follow from it, so they are not stored one by one.
#[derive(Clone, Copy)]
struct Run {
    col: u32,
    /// First row and the creation index of its candidate.
    j0: i64,
    first: u32,
    /// Number of rows.
    n: u32,
    /// Height of the crossing below and the span up to the one above.
    bottom: f64,
    h: f64,
    /// Whether the crossing above, and the one below, is the margin's (else the cut's).
    top_up: bool,
    bottom_up: bool,
}

/// The candidate lattice: column `k` at `x = (k + ½)·cx`, rows at `y = (j + shift)·step` (odd
/// columns shifted half a step), each column's candidates as runs of consecutive rows.
struct Lattice {
    cx: f64,
    step: f64,
    /// Edge lengths at the margin and at the cut.
    e_upper: f64,
    e_lower: f64,
    runs: Vec<Run>,
    /// Per column: its runs (indices into `runs`), from the top.
    cols: Vec<Vec<u32>>,
    /// Per candidate (creation index): its run.
    run_of: Vec<u32>,
}

impl Lattice {
    fn shift(&self, k: usize) -> f64 {
        if k % 2 == 1 { 0.5 } else { 0.0 }
    }

    /// Height of row `j` in column `k`.
    fn y(&self, k: usize, j: i64) -> f64 {
        (j as f64 + self.shift(k)) * self.step
    }

    /// Size at height `y` of run `r`: graded from the cut's edge length at the bottom to the
    /// margin's at the top, by the loops the span lies between.
    fn size(&self, r: &Run, y: f64) -> f64 {
        let t = (y - r.bottom) / r.h;
        match (r.top_up, r.bottom_up) {
            (true, false) => self.e_lower + (self.e_upper - self.e_lower) * t,
            (true, true) => self.e_upper,
            (false, false) => self.e_lower,
            (false, true) => 0.5 * (self.e_upper + self.e_lower),
        }
    }

    /// Position and size of candidate `idx`.
    fn at(&self, idx: u32) -> ([f64; 2], f64) {
        let r = &self.runs[self.run_of[idx as usize] as usize];
        let k = r.col as usize;
        let y = self.y(k, r.j0 + (idx - r.first) as i64);
        ([(k as f64 + 0.5) * self.cx, y], self.size(r, y))
    }

    /// Marks in `out` (by creation index) candidates `c` closer to `p` than
    /// `k·(size of c + e)`, sizes being at most `e_max`: every candidate marked is that close
    /// (each is tested), though not every such candidate need be marked. Columns are taken
    /// outwards from `p`'s until one marks nothing, and in each column's runs the rows outwards
    /// from `p`'s height until one is not that close, so the work follows the marks.
    fn mark_within(
        &self,
        p: [f64; 2],
        (k, e, e_max): (f64, f64, f64),
        period: f64,
        out: &mut [bool],
    ) {
        let r = k * (e_max + e);
        let ncols = self.cols.len() as i64;
        let kq = (p[0] / self.cx - 0.5).round() as i64;
        let dk = ((r / self.cx).ceil() as i64 + 1).min(ncols / 2);
        for side in [1i64, -1] {
            let first = if side == 1 { 0 } else { 1 };
            for d in first..=dk {
                let col = (kq + side * d).rem_euclid(ncols) as usize;
                let dx = wrap((col as f64 + 0.5) * self.cx - p[0], period);
                if dx.abs() >= r || (!self.mark_column(col, dx, p, (k, e), out) && d > 0) {
                    break;
                }
            }
        }
    }

    /// [`Lattice::mark_within`] in column `col` (at `dx` from `p`): in each run, the rows
    /// outwards from the one nearest `p`'s height while they are close enough. Whether any
    /// was.
    fn mark_column(
        &self,
        col: usize,
        dx: f64,
        p: [f64; 2],
        (k, e): (f64, f64),
        out: &mut [bool],
    ) -> bool {
        let shift = self.shift(col);
        let mut any = false;
        for &ri in &self.cols[col] {
            let run = &self.runs[ri as usize];
            let mut mark = |j: i64| {
                let y = self.y(col, j);
                let dy = y - p[1];
                let rc = k * (self.size(run, y) + e);
                let close = dx * dx + dy * dy < rc * rc;
                if close {
                    out[(run.first + (j - run.j0) as u32) as usize] = true;
                    any = true;
                }
                close
            };
            let last = run.j0 + run.n as i64 - 1;
            let jc = ((p[1] / self.step - shift).round() as i64).clamp(run.j0, last);
            let mut j = jc;
            while j <= last && mark(j) {
                j += 1;
            }
            let mut j = jc - 1;
            while j >= run.j0 && mark(j) {
                j -= 1;
            }
        }
        any
    }
}

/// The creation indices of the candidates ordered by priority, then `x`, `y` (`pos`) and
/// creation index, from `keys` = (priority's bits, creation index) per candidate (a stable
/// radix sort on the priority's upper bits, the priorities being positive, then the rare runs
/// that agree there by the whole priority and the rest): the order the greedy acceptance
/// depends on.
fn candidate_order(mut keys: Vec<(u64, u32)>, pos: impl Fn(u32) -> [f64; 2]) -> Vec<u32> {
    debug_assert!(keys.iter().all(|k| f64::from_bits(k.0) >= 0.0));
    // The radix passes cover the priority's sign, exponent and upper mantissa bits only (3 of
    // 11 bits instead of 6): priorities that agree there are rare and sorted in full below.
    const LOW_BITS: u32 = 29;
    crate::radix::sort_by_key(&mut keys, |k| k.0 >> LOW_BITS);
    let mut i = 0;
    while i < keys.len() {
        let mut j = i + 1;
        while j < keys.len() && keys[j].0 >> LOW_BITS == keys[i].0 >> LOW_BITS {
            j += 1;
        }
        if j - i > 1 {
            keys[i..j].sort_unstable_by(|a, b| {
                let (p, q) = (pos(a.1), pos(b.1));
                a.0.cmp(&b.0)
                    .then(p[0].total_cmp(&q[0]))
                    .then(p[1].total_cmp(&q[1]))
                    .then(a.1.cmp(&b.1))
            });
        }
        i = j;
    }
    keys.into_iter().map(|k| k.1).collect()
}

/// Graded Poisson-disk sample of the region between the upper polyline `up` and the lower
/// polyline `lo` (chart coordinates, both closed and running once around the periodic strip).
/// Returned points have `x` in `[0, period)`.
pub fn sample(up: &[[f64; 2]], lo: &[[f64; 2]], period: f64, o: &SampleOptions) -> Vec<[f64; 2]> {
    sample_with(up, lo, period, o, true)
}

/// The candidates of a sample: a column-aligned hexagonal lattice of step `¼·e_min` inside the
/// region (each candidate's size graded from the cut's edge length to the margin's), the
/// candidates' sort keys (priority: 1 − its height in its column's span, the margin first) and
/// the region's height range.
struct Candidates {
    lattice: Lattice,
    keys: Vec<(u64, u32)>,
    y_range: (f64, f64),
}

fn candidates(up: &[[f64; 2]], lo: &[[f64; 2]], period: f64, o: &SampleOptions) -> Candidates {
    let step = 0.25 * o.e_upper.min(o.e_lower);
    let ncols = ((period / (step * 0.866)).ceil() as usize).max(3);
    let cx = period / ncols as f64;
    // Crossings of every column x_k = (k + ½)·cx with both loops: (y, is_upper).
    let mut cross: Vec<Vec<(f64, bool)>> = vec![Vec::new(); ncols];
    for (is_up, lp) in [(true, up), (false, lo)] {
        let n = lp.len();
        for i in 0..n {
            let a = lp[i];
            let b = lp[(i + 1) % n];
            let dx = wrap(b[0] - a[0], period);
            if dx == 0.0 {
                continue;
            }
            let (x0, x1) = (a[0].min(a[0] + dx), a[0].max(a[0] + dx));
            let k0 = (x0 / cx - 0.5).ceil() as i64;
            let k1 = (x1 / cx - 0.5).ceil() as i64;
            for k in k0..k1 {
                let xk = (k as f64 + 0.5) * cx;
                let y = a[1] + (xk - a[0]) / dx * (b[1] - a[1]);
                cross[k.rem_euclid(ncols as i64) as usize].push((y, is_up));
            }
        }
    }
    let mut keys: Vec<(u64, u32)> = Vec::new();
    let mut lattice = Lattice {
        cx,
        step,
        e_upper: o.e_upper,
        e_lower: o.e_lower,
        runs: Vec::new(),
        cols: vec![Vec::new(); ncols],
        run_of: Vec::new(),
    };
    let mut y_lo = f64::INFINITY;
    let mut y_hi = f64::NEG_INFINITY;
    for (k, c) in cross.iter_mut().enumerate() {
        c.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let shift = lattice.shift(k);
        let (mut pu, mut pl) = (false, false);
        for w in 0..c.len() {
            if c[w].1 {
                pu = !pu;
            } else {
                pl = !pl;
            }
            if !pu || pl || w + 1 >= c.len() {
                continue;
            }
            let (top, bottom) = (c[w], c[w + 1]);
            let h = top.0 - bottom.0;
            if h <= 0.0 {
                continue;
            }
            y_lo = y_lo.min(bottom.0);
            y_hi = y_hi.max(top.0);
            let mut run = Run {
                col: k as u32,
                j0: 0,
                first: keys.len() as u32,
                n: 0,
                bottom: bottom.0,
                h,
                top_up: top.1,
                bottom_up: bottom.1,
            };
            let j0 = floor_i64(bottom.0 / step - shift) + 1;
            let j1 = ceil_i64(top.0 / step - shift) - 1;
            // The heights rise with the row, so the rows kept are consecutive.
            for j in j0..=j1 {
                let y = (j as f64 + shift) * step;
                if y <= bottom.0 || y >= top.0 {
                    continue;
                }
                if run.n == 0 {
                    run.j0 = j;
                }
                debug_assert_eq!(j, run.j0 + run.n as i64);
                let t = (y - bottom.0) / h;
                keys.push(((1.0 - t).to_bits(), run.first + run.n));
                run.n += 1;
            }
            if run.n > 0 {
                let ri = lattice.runs.len() as u32;
                lattice.cols[k].push(ri);
                lattice
                    .run_of
                    .extend(std::iter::repeat_n(ri, run.n as usize));
                lattice.runs.push(run);
            }
        }
    }
    Candidates {
        lattice,
        keys,
        y_range: (y_lo, y_hi),
    }
}

/// [`sample`], with `skip_sure` whether the candidates an accepted point is sure to reject are
/// skipped without their test (the same sample either way, faster with).
fn sample_with(
    up: &[[f64; 2]],
    lo: &[[f64; 2]],
    period: f64,
    o: &SampleOptions,
    skip_sure: bool,
) -> Vec<[f64; 2]> {
    let e_max = o.e_upper.max(o.e_lower);
    let Candidates {
        lattice,
        keys,
        y_range: (mut y_lo, mut y_hi),
    } = candidates(up, lo, period, o);
    if keys.is_empty() {
        return Vec::new();
    }
    let n_cand = keys.len();
    let order = candidate_order(keys, |i| lattice.at(i).0);
    // Greedy acceptance against loop vertices, loop edges and accepted points.
    let cell = o.radius.max(o.clearance) * e_max;
    for lp in [up, lo] {
        for p in lp {
            y_lo = y_lo.min(p[1]);
            y_hi = y_hi.max(p[1]);
        }
    }
    let mut pts: Vec<([f64; 2], f64)> = Vec::new();
    let mut pgrid = Grid::new(period, y_lo, y_hi, cell);
    let mut sgrid = Grid::new(period, y_lo, y_hi, cell);
    let mut segs: Vec<([f64; 2], [f64; 2])> = Vec::new();
    for (lp, e) in [(up, o.e_upper), (lo, o.e_lower)] {
        let n = lp.len();
        for i in 0..n {
            let a = lp[i];
            let b = lp[(i + 1) % n];
            let id = pts.len() as u32;
            pgrid.insert_box(id, a, a);
            pts.push(([a[0].rem_euclid(period), a[1]], e));
            let sid = segs.len() as u32;
            let bu = [a[0] + wrap(b[0] - a[0], period), b[1]];
            sgrid.insert_box(sid, a, bu);
            segs.push((a, b));
        }
    }
    let n_fixed = pts.len();
    // Candidates an accepted point is sure to reject (closer than 0.999 of the disk radius
    // with their own size, the margin covering rounding), marked by creation index: most of
    // the fine lattice, skipped without a grid search. The acceptances are those of the full
    // test alone.
    let mut rejected = vec![false; n_cand];
    for idx in order {
        if rejected[idx as usize] {
            continue;
        }
        let (p, e) = lattice.at(idx);
        let ok_pts = pgrid.near(p, |id| {
            let (q, eq) = pts[id as usize];
            let r = o.radius * 0.5 * (e + eq);
            let dx = wrap(p[0] - q[0], period);
            let dy = p[1] - q[1];
            dx * dx + dy * dy >= r * r
        });
        if !ok_pts {
            continue;
        }
        let c2 = (o.clearance * e).powi(2);
        let ok_segs = sgrid.near(p, |id| {
            let (a, b) = segs[id as usize];
            seg_dist2(p, a, b, period) >= c2
        });
        if !ok_segs {
            continue;
        }
        let id = pts.len() as u32;
        pgrid.insert_box(id, p, p);
        pts.push((p, e));
        if skip_sure {
            let k = 0.999 * o.radius * 0.5;
            lattice.mark_within(p, (k, e, e_max), period, &mut rejected);
        }
    }
    pts[n_fixed..].iter().map(|&(p, _)| p).collect()
}

#[cfg(test)]
mod tests;
