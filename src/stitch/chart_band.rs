//! Glue of the default band ([`super::PointGeneration::Chart`]): loops into the chart, graded
//! sample, constrained Delaunay triangulation in the annulus plane, harmonic lift to 3D.

use super::chart::{Lift, RefCurve, convex_reference, harmonic, wrap};
use super::chart_sample::{SampleOptions, sample};
use super::{Band, BandLoops, BandVertex, StitchOptions, loop_cdt, mean_edge, smooth, smooth_dirs};
use crate::cut::ToothFrame;
use crate::{Error, Result};
use glam::DVec3;
use std::f64::consts::TAU;

/// Smallest angle (degrees) the chart triangulation is refined to (Delaunay refinement in the
/// annulus plane, which is conformal to the chart). Measured on the 20 eval jaws: the band's
/// smallest 3D angle is ≥ 5° on 210 of 219 teeth with it, 201 without (before the untangling of
/// `fuse::untangle`); 15° gives the same count with a lower median per-tooth minimum (16.7° vs
/// 19.0°); 10° gave the same as 20° on the first 6 jaws.
const REFINE_DEG: f64 = 20.0;

/// Finest spacing of the band's sample at the margin, as a fraction of the cut's mean edge
/// length. The sample grades from the margin's mean edge length to the cut's; on dense exports
/// (margin edges of 0.05-0.06 mm against a CBCT cut of ~0.27 mm, the foreign jaws and the dense
/// phantom exports) that made the band 5-6 times finer at the top than at the bottom, and its
/// candidate lattice (a quarter of the finest spacing) 9 times as large as on the clean phantom's
/// 0.15 mm margin, for a band whose shape (a smooth profile a millimetre or two high) needs none
/// of it: every margin vertex is still a band vertex, the interior points start no finer than a
/// third of the cut's spacing. Measured on the foreign jaws (true transforms): ~40 % fewer band
/// faces, their stitching ~30 % faster, no crossing added and the trims within their budget
/// (0.5 instead of 0.35 trimmed 0.503 % of one crown); the clean and coarse phantom crowns
/// (mean margin edges ≥ 0.15 mm) are not affected, the rough phantom exports' (~0.09 mm) barely.
const MARGIN_SPACING_FLOOR: f64 = 0.35;

/// The loops, ordered counter-clockwise about the axis, with their caller indices.
pub(super) struct OrderedLoops<'a> {
    pub uo: &'a [u32],
    pub lo: &'a [u32],
    pub up_pts: &'a [DVec3],
    pub lo_pts: &'a [DVec3],
    pub up_dirs: &'a [DVec3],
    pub lo_dirs: &'a [DVec3],
}

/// The chart band and how many of its faces fold over.
pub(super) struct ChartBand {
    pub band: Band,
    /// Faces the lift folded over (see [`folded_faces`]).
    pub folded: usize,
}

/// Builds the chart band; an error means the loops do not project to a simple annulus in the
/// chart (the caller falls back to the loft rings).
pub(super) fn chart_band(
    loops: &BandLoops,
    frame: &ToothFrame,
    opts: &StitchOptions,
    o: &OrderedLoops,
) -> Result<ChartBand> {
    let up_s = smooth(o.up_pts, 8);
    let up_d = smooth_dirs(o.up_dirs, 8);
    let lo_s = smooth(o.lo_pts, 4);
    let lo_d = smooth_dirs(o.lo_dirs, 4);
    let hull_pts: Vec<DVec3> = up_s.iter().chain(&lo_s).copied().collect();
    let curve = RefCurve::new(frame, &convex_reference(frame, &hull_pts, 0.1, 200))?;
    let lift = Lift::new(
        frame,
        curve,
        (&up_s, &up_d),
        (&lo_s, &lo_d),
        opts.tangent_scale,
    );
    let (up_c, up_r) = chart_loop(&lift, o.up_pts, "margin")?;
    let (lo_c, lo_r) = chart_loop(&lift, o.lo_pts, "cut")?;
    let e_lower = mean_edge(o.lo_pts);
    let so = SampleOptions {
        e_upper: mean_edge(o.up_pts).max(MARGIN_SPACING_FLOOR * e_lower),
        e_lower,
        radius: 0.8,
        clearance: 0.5,
    };
    let t = triangulate(loops, o, &so, lift.period(), up_c, lo_c)?;
    let n = Numbering {
        nu: loops.upper.len(),
        nl: loops.lower.len(),
        ni: t.band.points.len(),
    };
    let (chart, fixed, offset) = chart_positions(&n, o, &t, &up_r, &lo_r, lift.period());
    let mut band = t.band;
    let tris: Vec<[u32; 3]> = band
        .triangles
        .iter()
        .map(|tri| tri.map(|b| n.id(b)))
        .collect();
    // Lift: Hermite profile + harmonic correction to the real loop vertices.
    let mut values: Vec<f64> = (0..n.len())
        .map(|i| {
            if fixed[i] {
                offset[i] - lift.profile_offset(chart[i])
            } else {
                0.0
            }
        })
        .collect();
    harmonic(&chart, lift.period(), &tris, &fixed, &mut values);
    let first = n.nu + n.nl;
    for i in 0..n.ni {
        if !fixed[first + i] {
            let c = chart[first + i];
            band.points[i] = lift.point(c, lift.profile_offset(c) + values[first + i]);
        }
    }
    let folded = folded_faces(&band, loops, &tris, &chart, &lift);
    Ok(ChartBand { band, folded })
}

/// The chart positions of a loop's points (unwrapped to run once around, `x` increasing by
/// the period) and their offsets from the reference surface; an error names the loop (`what`)
/// when it does not run once around the chart.
fn chart_loop(lift: &Lift, pts: &[DVec3], what: &str) -> Result<(Vec<[f64; 2]>, Vec<f64>)> {
    let period = lift.period();
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(pts.len());
    let mut off = Vec::with_capacity(pts.len());
    for &p in pts {
        let (mut c, r) = lift.chart(p);
        if let Some(prev) = out.last() {
            c[0] = prev[0] + wrap(c[0] - prev[0], period);
        }
        out.push(c);
        off.push(r);
    }
    let (first, last) = (out[0][0], out[out.len() - 1][0]);
    let total = last + wrap(first - last, period) - first;
    if (total - period).abs() > 1e-6 * period {
        return Err(Error::InvalidArgument(format!(
            "{what} loop runs {:.2} times around the chart",
            total / period
        )));
    }
    Ok((out, off))
}

/// The band triangulated in the annulus plane, with the chart loops it was made from.
struct Triangulated {
    band: Band,
    /// Per band point: its plane position and the index of its sample point (`None` for a
    /// chord split).
    origin: Vec<super::cdt::PointOrigin>,
    /// The sample points (chart coordinates).
    inner: Vec<[f64; 2]>,
    /// The chart loops as triangulated (made monotone where the first try folded).
    up_c: Vec<[f64; 2]>,
    lo_c: Vec<[f64; 2]>,
    /// The chart height mapped to the plane's unit circle.
    y0: f64,
}

/// Samples and triangulates the band between the chart loops `up_c` and `lo_c`: first the
/// loops as they chart; if a loop folds back over itself there, again with its chart
/// positions made monotone along the loop (least-squares, pool adjacent violators) and the
/// margin kept above the cut (a clipped, jagged margin or a deep notch can do both).
fn triangulate(
    loops: &BandLoops,
    o: &OrderedLoops,
    so: &SampleOptions,
    period: f64,
    mut up_c: Vec<[f64; 2]>,
    mut lo_c: Vec<[f64; 2]>,
) -> Result<Triangulated> {
    let mut attempt = 0;
    loop {
        let y0 = lo_c.iter().map(|c| c[1]).fold(f64::INFINITY, f64::min);
        let plane = |c: [f64; 2]| {
            let r = (TAU * (c[1] - y0) / period).exp();
            let a = TAU * c[0] / period;
            [r * a.cos(), r * a.sin()]
        };
        let up_xy: Vec<[f64; 2]> = up_c.iter().map(|&c| plane(c)).collect();
        let lo_xy: Vec<[f64; 2]> = lo_c.iter().map(|&c| plane(c)).collect();
        // The loops first: where they do not bound an annulus, no point is sampled.
        let filled = loop_cdt(&up_xy, &lo_xy, o.uo, o.lo).and_then(|lc| {
            let inner = sample(&up_c, &lo_c, period, so);
            let interior: Vec<([f64; 2], DVec3, f64)> = inner
                .iter()
                .map(|&c| (plane(c), DVec3::ZERO, 0.0))
                .collect();
            Ok((inner, lc.fill(&interior, loops, REFINE_DEG)?))
        });
        match filled {
            Ok((inner, (band, origin))) => {
                return Ok(Triangulated {
                    band,
                    origin,
                    inner,
                    up_c,
                    lo_c,
                    y0,
                });
            }
            Err(e) if attempt > 0 => return Err(e),
            Err(_) => {
                attempt += 1;
                monotone_x(&mut up_c, period);
                monotone_x(&mut lo_c, period);
                separate_loops(&mut up_c, &lo_c, period, 0.5 * so.e_upper.min(so.e_lower));
            }
        }
    }
}

/// Band vertex numbering of the lift: the upper loop's `nu` vertices, the lower loop's `nl`,
/// then the `ni` interior points.
struct Numbering {
    nu: usize,
    nl: usize,
    ni: usize,
}

impl Numbering {
    fn len(&self) -> usize {
        self.nu + self.nl + self.ni
    }

    fn id(&self, b: BandVertex) -> u32 {
        match b {
            BandVertex::Upper(i) => i,
            BandVertex::Lower(i) => self.nu as u32 + i,
            BandVertex::Interior(i) => (self.nu + self.nl) as u32 + i,
        }
    }
}

/// Per band vertex (numbered by `n`): its chart position, whether it is fixed (a loop vertex)
/// and its offset from the reference surface (loop vertices only).
fn chart_positions(
    n: &Numbering,
    o: &OrderedLoops,
    t: &Triangulated,
    up_r: &[f64],
    lo_r: &[f64],
    period: f64,
) -> (Vec<[f64; 2]>, Vec<bool>, Vec<f64>) {
    let (nu, nl) = (n.nu, n.nl);
    let mut chart = vec![[0.0; 2]; n.len()];
    let mut fixed = vec![true; n.len()];
    let mut offset = vec![0.0; n.len()];
    for (k, &i) in o.uo.iter().enumerate() {
        chart[i as usize] = t.up_c[k];
        offset[i as usize] = up_r[k];
    }
    for (k, &i) in o.lo.iter().enumerate() {
        chart[nu + i as usize] = t.lo_c[k];
        offset[nu + i as usize] = lo_r[k];
    }
    for i in 0..n.ni {
        fixed[nu + nl + i] = false;
        chart[nu + nl + i] = match t.origin[i].1 {
            Some(k) => t.inner[k as usize],
            None => {
                // A chord split: a free point at its plane position.
                let xy = t.origin[i].0;
                let x = xy[1].atan2(xy[0]).rem_euclid(TAU) / TAU * period;
                let y = t.y0 + (xy[0].hypot(xy[1])).ln() * period / TAU;
                [x, y]
            }
        };
    }
    (chart, fixed, offset)
}

/// Band faces whose lifted normal points to the other side of the reference curve than most
/// faces' do, each judged at the outward normal where its chart centroid lies: where the lift
/// folded the band over.
fn folded_faces(
    band: &Band,
    loops: &BandLoops,
    tris: &[[u32; 3]],
    chart: &[[f64; 2]],
    lift: &Lift,
) -> usize {
    let (nu, nl) = (loops.upper.len(), loops.lower.len());
    let period = lift.period();
    let pos = |i: u32| {
        let i = i as usize;
        if i < nu {
            loops.upper[i]
        } else if i < nu + nl {
            loops.lower[i - nu]
        } else {
            band.points[i - nu - nl]
        }
    };
    let (mut plus, mut minus) = (0usize, 0usize);
    for t in tris {
        let [a, b, c] = t.map(pos);
        let x0 = chart[t[0] as usize][0];
        let xm = x0
            + (wrap(chart[t[1] as usize][0] - x0, period)
                + wrap(chart[t[2] as usize][0] - x0, period))
                / 3.0;
        if (b - a).cross(c - a).dot(lift.outward(xm)) > 0.0 {
            plus += 1;
        } else {
            minus += 1;
        }
    }
    plus.min(minus)
}

/// Makes the chart `x` of a closed loop (unwrapped, running once over `period`) strictly
/// increasing along the loop with the least change: pool-adjacent-violators isotonic regression,
/// then a tiny spread inside each pooled block.
fn monotone_x(c: &mut [[f64; 2]], period: f64) {
    let n = c.len();
    // Blocks of (sum, count).
    let mut blocks: Vec<(f64, usize)> = Vec::with_capacity(n);
    for p in c.iter() {
        blocks.push((p[0], 1));
        while blocks.len() > 1 {
            let (s1, n1) = blocks[blocks.len() - 1];
            let (s0, n0) = blocks[blocks.len() - 2];
            if s0 / n0 as f64 >= s1 / n1 as f64 {
                blocks.pop();
                let last = blocks.len() - 1;
                blocks[last] = (s0 + s1, n0 + n1);
            } else {
                break;
            }
        }
    }
    let mut k = 0;
    for &(s, m) in &blocks {
        for _ in 0..m {
            c[k][0] = s / m as f64;
            k += 1;
        }
    }
    // Strictly increasing, by a step far above rounding and far below any edge, and closing
    // within one period.
    let eps = 1e-7 * period;
    for k in 1..n {
        c[k][0] = c[k][0].max(c[k - 1][0] + eps);
    }
    let span = c[n - 1][0] - c[0][0];
    let room = period - eps;
    if span > room {
        let x0 = c[0][0];
        for p in c.iter_mut() {
            p[0] = x0 + (p[0] - x0) * room / span;
        }
    }
}

/// Raises margin chart points that lie below the cut loop (a notch reaching lower than the
/// cut) to just above it, so the two loops bound an annulus; the lift still meets the real
/// loop vertices.
fn separate_loops(up: &mut [[f64; 2]], lo: &[[f64; 2]], period: f64, gap: f64) {
    // The cut loop's height as a function of x (its x is increasing after `monotone_x`).
    let x0 = lo[0][0];
    let mut pts: Vec<(f64, f64)> = lo
        .iter()
        .map(|c| ((c[0] - x0).rem_euclid(period), c[1]))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The higher of the two cut points around x (conservative between them).
    let height = |x: f64| {
        let x = (x - x0).rem_euclid(period);
        let k = pts.partition_point(|p| p.0 <= x);
        let (a, b) = if k == 0 || k == pts.len() {
            (pts[pts.len() - 1], pts[0])
        } else {
            (pts[k - 1], pts[k])
        };
        a.1.max(b.1)
    };
    for p in up.iter_mut() {
        p[1] = p[1].max(height(p[0]) + gap);
    }
}

#[cfg(test)]
mod tests {
    use crate::cut::ToothFrame;
    use crate::stitch::{BandLoops, BandVertex, StitchOptions, build_band};
    use glam::DVec3;
    use std::f64::consts::TAU;

    /// `n` points of the circle of radius 4 about the z axis at height `z`.
    fn circle(n: usize, z: f64) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let a = TAU * i as f64 / n as f64;
                DVec3::new(4.0 * a.cos(), 4.0 * a.sin(), z)
            })
            .collect()
    }

    /// The smallest distance between two interior points of the band between a margin of
    /// `n_upper` vertices at z = 0 and a cut of 100 vertices 3 mm below, on a cylinder, and the
    /// cut's edge length; with every loop vertex checked to be a band vertex.
    fn closest_interior_points(n_upper: usize) -> (f64, f64) {
        let upper = circle(n_upper, 0.0);
        let lower = circle(100, -3.0);
        let loops = BandLoops {
            upper: &upper,
            upper_dir: &vec![DVec3::Z; upper.len()],
            lower: &lower,
            lower_dir: &vec![DVec3::Z; lower.len()],
            chords: &[],
        };
        let frame = ToothFrame::new(DVec3::ZERO, DVec3::Z);
        let band = build_band(&loops, &frame, &StitchOptions::default())
            .expect("band")
            .band;
        let (mut up, mut lo) = (vec![false; upper.len()], vec![false; lower.len()]);
        for v in band.triangles.iter().flatten() {
            match *v {
                BandVertex::Upper(i) => up[i as usize] = true,
                BandVertex::Lower(i) => lo[i as usize] = true,
                BandVertex::Interior(_) => {}
            }
        }
        assert!(
            up.iter().chain(&lo).all(|&s| s),
            "a loop vertex not in the band"
        );
        let p = &band.points;
        let mut closest = f64::INFINITY;
        for i in 0..p.len() {
            for q in &p[i + 1..] {
                closest = closest.min(p[i].distance(*q));
            }
        }
        (closest, lower[0].distance(lower[1]))
    }

    #[test]
    fn a_dense_margin_does_not_make_the_band_interior_finer_than_the_floor() {
        // Margin edges of 0.042 mm, cut edges of 0.25 mm: without the floor the interior points
        // at the top would lie ~0.8 x 0.042 mm apart.
        // With the floor they lie at least the sample's disk radius (0.8 of the spacing) times
        // the floor apart: 0.28 of the cut's edge length (0.076 mm measured; 0.036 without).
        let (closest, e_lower) = closest_interior_points(600);
        assert!(closest > 0.25 * e_lower, "{closest} against {e_lower}");
        // A margin coarser than the floor keeps its own spacing (0.17 mm edges).
        let (closest, _) = closest_interior_points(150);
        assert!(closest > 0.6 * TAU * 4.0 / 150.0, "{closest}");
    }
}
