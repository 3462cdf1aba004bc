//! Tests of the chart sampling.

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
    let keys = (0..cand.len() as u32)
        .map(|i| (cand[i as usize].0.to_bits(), i))
        .collect();
    assert_eq!(candidate_order(keys, |i| cand[i as usize].1), expect);
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
