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

/// The candidate lattice by column: column `k` at `x = (k + ½)·cx`, rows at `y = (j + shift)·step`
/// (odd columns shifted half a step), each column's candidates as runs of consecutive rows.
struct Lattice {
    cx: f64,
    step: f64,
    /// Per column: (first row, creation index of its candidate, number of rows).
    runs: Vec<Vec<(i64, u32, u32)>>,
}

impl Lattice {
    fn shift(&self, k: usize) -> f64 {
        if k % 2 == 1 { 0.5 } else { 0.0 }
    }

    /// Records candidate `idx` at column `k`, row `j` (rows of a run pushed in order).
    fn push(&mut self, k: usize, j: i64, idx: u32) {
        let runs = &mut self.runs[k];
        if let Some(last) = runs.last_mut()
            && last.0 + last.2 as i64 == j
            && last.1 + last.2 == idx
        {
            last.2 += 1;
            return;
        }
        runs.push((j, idx, 1));
    }

    /// Marks in `out` (by creation index) candidates `c` of `cand` closer to `p` than
    /// `k·(size of c + e)`, sizes being at most `e_max`: every candidate marked is that close
    /// (each is tested), though not every such candidate need be marked. Columns are taken
    /// outwards from `p`'s until one marks nothing, and in each column's runs the rows outwards
    /// from `p`'s height until one is not that close, so the work follows the marks.
    fn mark_within(
        &self,
        p: [f64; 2],
        (k, e, e_max): (f64, f64, f64),
        period: f64,
        cand: &[(f64, [f64; 2], f64)],
        out: &mut [bool],
    ) {
        let r = k * (e_max + e);
        let ncols = self.runs.len() as i64;
        let kq = (p[0] / self.cx - 0.5).round() as i64;
        let dk = ((r / self.cx).ceil() as i64 + 1).min(ncols / 2);
        for side in [1i64, -1] {
            let first = if side == 1 { 0 } else { 1 };
            for d in first..=dk {
                let col = (kq + side * d).rem_euclid(ncols) as usize;
                let dx = wrap((col as f64 + 0.5) * self.cx - p[0], period);
                if dx.abs() >= r || (!self.mark_column(col, dx, p, (k, e), cand, out) && d > 0) {
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
        cand: &[(f64, [f64; 2], f64)],
        out: &mut [bool],
    ) -> bool {
        let shift = self.shift(col);
        let mut any = false;
        let mut mark = |j: i64, j0: i64, first: u32| {
            let dy = (j as f64 + shift) * self.step - p[1];
            let idx = (first + (j - j0) as u32) as usize;
            let rc = k * (cand[idx].2 + e);
            let close = dx * dx + dy * dy < rc * rc;
            if close {
                out[idx] = true;
                any = true;
            }
            close
        };
        for &(j0, first, n) in &self.runs[col] {
            let last = j0 + n as i64 - 1;
            let jc = ((p[1] / self.step - shift).round() as i64).clamp(j0, last);
            let mut j = jc;
            while j <= last && mark(j, j0, first) {
                j += 1;
            }
            let mut j = jc - 1;
            while j >= j0 && mark(j, j0, first) {
                j -= 1;
            }
        }
        any
    }
}

/// The creation indices of `cand` ordered by priority, then `x`, `y` and creation index (a
/// stable radix sort on the priority's upper bits, the priorities being positive, then the rare
/// runs that agree there by the whole priority and the rest): the order the greedy acceptance
/// depends on.
fn candidate_order(cand: &[(f64, [f64; 2], f64)]) -> Vec<u32> {
    debug_assert!(cand.iter().all(|c| c.0 >= 0.0));
    let mut keys: Vec<(u64, u32)> = (0..cand.len() as u32)
        .map(|i| (cand[i as usize].0.to_bits(), i))
        .collect();
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
                let (p, q) = (cand[a.1 as usize].1, cand[b.1 as usize].1);
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
/// region, each with its priority (1 − its height in its column's span, the margin first) and
/// size (graded from the cut's edge length to the margin's); the lattice's rows by column; and
/// the region's height range.
struct Candidates {
    cand: Vec<(f64, [f64; 2], f64)>,
    lattice: Lattice,
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
    let mut cand: Vec<(f64, [f64; 2], f64)> = Vec::new();
    let mut lattice = Lattice {
        cx,
        step,
        runs: vec![Vec::new(); ncols],
    };
    let mut y_lo = f64::INFINITY;
    let mut y_hi = f64::NEG_INFINITY;
    for (k, c) in cross.iter_mut().enumerate() {
        c.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let xk = (k as f64 + 0.5) * cx;
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
            let j0 = floor_i64(bottom.0 / step - shift) + 1;
            let j1 = ceil_i64(top.0 / step - shift) - 1;
            for j in j0..=j1 {
                let y = (j as f64 + shift) * step;
                if y <= bottom.0 || y >= top.0 {
                    continue;
                }
                let t = (y - bottom.0) / h;
                let size = match (top.1, bottom.1) {
                    (true, false) => o.e_lower + (o.e_upper - o.e_lower) * t,
                    (true, true) => o.e_upper,
                    (false, false) => o.e_lower,
                    (false, true) => 0.5 * (o.e_upper + o.e_lower),
                };
                lattice.push(k, j, cand.len() as u32);
                cand.push((1.0 - t, [xk, y], size));
            }
        }
    }
    Candidates {
        cand,
        lattice,
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
        cand,
        lattice,
        y_range: (mut y_lo, mut y_hi),
    } = candidates(up, lo, period, o);
    if cand.is_empty() {
        return Vec::new();
    }
    let order = candidate_order(&cand);
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
    let mut rejected = vec![false; cand.len()];
    for idx in order {
        if rejected[idx as usize] {
            continue;
        }
        let (_, p, e) = cand[idx as usize];
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
            lattice.mark_within(p, (k, e, e_max), period, &cand, &mut rejected);
        }
    }
    pts[n_fixed..].iter().map(|&(p, _)| p).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chart band's radius and clearance with the given loop edge lengths.
    fn options(e_upper: f64, e_lower: f64) -> SampleOptions {
        SampleOptions {
            e_upper,
            e_lower,
            radius: 0.8,
            clearance: 0.5,
        }
    }

    /// With sizes 8x apart from margin to cut, the sample covers the band: no spot of the
    /// region is farther than ~the local size from a sample or loop point, near the fine margin
    /// as near the coarse cut.
    #[test]
    fn graded_sample_covers_the_band() {
        let period = 10.0;
        let n_up = 200;
        let up: Vec<[f64; 2]> = (0..n_up)
            .map(|i| [period * i as f64 / n_up as f64, 2.0])
            .collect();
        let lo: Vec<[f64; 2]> = (0..25).map(|i| [period * i as f64 / 25.0, 0.0]).collect();
        let o = options(0.05, 0.4);
        let s = sample(&up, &lo, period, &o);
        let all: Vec<[f64; 2]> = s.iter().chain(&up).chain(&lo).copied().collect();
        let size = |y: f64| o.e_lower + (o.e_upper - o.e_lower) * (y / 2.0);
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            for j in 1..80 {
                let q = [period * i as f64 / 200.0, 2.0 * j as f64 / 80.0];
                let d = all
                    .iter()
                    .map(|p| (wrap(p[0] - q[0], period).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d / size(q[1]));
            }
        }
        assert!(worst < 1.2, "a gap of {worst:.2} local sizes");
        // And it is graded: many more points in the top tenth than in the bottom tenth.
        let top = s.iter().filter(|p| p[1] > 1.8).count();
        let bottom = s.iter().filter(|p| p[1] < 0.2).count();
        assert!(
            top > 10 * bottom.max(1),
            "{top} near the margin, {bottom} near the cut"
        );
    }

    /// Wavy loops with sizes 1x to 8x apart: skipping the candidates an accepted point is sure
    /// to reject gives the very sample the full test gives.
    #[test]
    fn skipping_sure_rejections_changes_no_point() {
        let period = 12.0;
        for (e_up, e_lo, n_up, n_lo) in [
            (0.05, 0.4, 240, 30),
            (0.1, 0.1, 120, 120),
            (0.3, 0.06, 40, 200),
        ] {
            let up: Vec<[f64; 2]> = (0..n_up)
                .map(|i| {
                    let x = period * i as f64 / n_up as f64;
                    [x, 1.5 + 0.3 * (x * 2.1).sin()]
                })
                .collect();
            let lo: Vec<[f64; 2]> = (0..n_lo)
                .map(|i| {
                    let x = period * i as f64 / n_lo as f64;
                    [x, -0.2 * (x * 0.7).cos()]
                })
                .collect();
            let o = options(e_up, e_lo);
            let fast = sample_with(&up, &lo, period, &o, true);
            let full = sample_with(&up, &lo, period, &o, false);
            assert!(full.len() > 100, "{} points", full.len());
            assert_eq!(fast, full, "sizes {e_up} / {e_lo}");
        }
    }

    /// The radix order of the candidates is the comparison sort's by priority, x, y and
    /// creation index, repeated priorities included.
    #[test]
    fn candidate_order_is_the_comparison_order() {
        let mut rng = crate::phantom::rng::Rng::new(5);
        let cand: Vec<(f64, [f64; 2], f64)> = (0..5000)
            .map(|_| {
                // Few distinct priorities and x values, so ties reach every key; some
                // priorities differ only in their lowest bits (below the radix passes).
                let mut prio = rng.below(50) as f64 / 49.0;
                if rng.below(3) == 0 {
                    prio = f64::from_bits(prio.to_bits() + rng.below(1 << 20) as u64);
                }
                let x = rng.below(7) as f64;
                (prio, [x, rng.range(-1.0, 1.0)], 0.1)
            })
            .collect();
        let mut expect: Vec<u32> = (0..cand.len() as u32).collect();
        expect.sort_by(|&a, &b| {
            let (p, q) = (cand[a as usize], cand[b as usize]);
            p.0.total_cmp(&q.0)
                .then(p.1[0].total_cmp(&q.1[0]))
                .then(p.1[1].total_cmp(&q.1[1]))
                .then(a.cmp(&b))
        });
        assert_eq!(candidate_order(&cand), expect);
    }

    #[test]
    fn sample_is_inside_spaced_and_clear_of_loops() {
        let period = 20.0;
        let up: Vec<[f64; 2]> = (0..200)
            .map(|i| {
                let x = period * i as f64 / 200.0;
                [x, 1.0 + 0.2 * (x * 3.0).sin()]
            })
            .collect();
        let lo: Vec<[f64; 2]> = (0..70)
            .map(|i| [period * i as f64 / 70.0, -0.3 * (x_of(i) * 0.5).cos()])
            .collect();
        fn x_of(i: usize) -> f64 {
            20.0 * i as f64 / 70.0
        }
        let o = options(0.1, 0.3);
        let s = sample(&up, &lo, period, &o);
        assert!(s.len() > 500, "{} points", s.len());
        for p in &s {
            let k = ((p[0] / period * 200.0).floor() as usize).min(199);
            let top = up[k][1].max(up[(k + 1) % 200][1]);
            let kl = ((p[0] / period * 70.0).floor() as usize).min(69);
            let bottom = lo[kl][1].min(lo[(kl + 1) % 70][1]);
            assert!(p[1] < top && p[1] > bottom, "{p:?} outside");
            for q in up.iter().chain(&lo) {
                let d = ((wrap(p[0] - q[0], period)).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                assert!(
                    d >= 0.8 * 0.5 * (0.1 + 0.1) - 1e-12,
                    "{p:?} too close to {q:?}"
                );
            }
        }
        for (i, p) in s.iter().enumerate() {
            for q in &s[i + 1..] {
                let d = ((wrap(p[0] - q[0], period)).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                assert!(d >= 0.8 * 0.1 - 1e-12);
            }
        }
    }
}
