//! The gingiva seen by the IOS: a height field over the horizontal plane (heights along the
//! occlusal direction) that meets each tooth at its scalloped margin, rises into papillae
//! between neighbours and falls away buccally and lingually into a ridge.

use glam::{DVec2, DVec3};

/// Margin of one tooth as a polar table around its centre in the horizontal plane.
#[derive(Clone, Debug)]
pub struct MarginPolar {
    center: DVec2,
    /// Horizontal distal direction of the tooth (unit).
    distal: DVec2,
    radius: Vec<f64>,
    height: Vec<f64>,
}

const BINS: usize = 180;

impl MarginPolar {
    /// From margin points (world, any frame with `occ` the occlusal direction) and the tooth's
    /// distal direction.
    pub fn new(margin: &[DVec3], occ: DVec3, distal: DVec3) -> MarginPolar {
        let h2 = |p: DVec3| DVec2::new(p.x, p.y);
        let c = margin.iter().fold(DVec2::ZERO, |a, p| a + h2(*p)) / margin.len() as f64;
        let mut samples: Vec<(f64, f64, f64)> = margin
            .iter()
            .map(|p| {
                let d = h2(*p) - c;
                (d.y.atan2(d.x), d.length(), p.dot(occ))
            })
            .collect();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut radius = vec![0.0; BINS];
        let mut height = vec![0.0; BINS];
        let n = samples.len();
        for b in 0..BINS {
            let ang =
                -std::f64::consts::PI + std::f64::consts::TAU * (b as f64 + 0.5) / BINS as f64;
            let i = samples.partition_point(|s| s.0 < ang);
            let (s0, s1) = (samples[(i + n - 1) % n], samples[i % n]);
            let mut a0 = s0.0;
            let mut a1 = s1.0;
            if a1 < ang {
                a1 += std::f64::consts::TAU;
            }
            if a0 > ang {
                a0 -= std::f64::consts::TAU;
            }
            let t = if a1 - a0 > 1e-12 {
                (ang - a0) / (a1 - a0)
            } else {
                0.5
            };
            radius[b] = s0.1 + t * (s1.1 - s0.1);
            height[b] = s0.2 + t * (s1.2 - s0.2);
        }
        let d = DVec2::new(distal.x, distal.y);
        MarginPolar {
            center: c,
            distal: if d.length() > 1e-9 {
                d.normalize()
            } else {
                DVec2::X
            },
            radius,
            height,
        }
    }

    /// Gingiva height contributed by this tooth at horizontal point `q`.
    fn term(&self, q: DVec2) -> f64 {
        let d = q - self.center;
        let r = d.length();
        if r > 16.0 {
            return f64::NEG_INFINITY;
        }
        let ang = d.y.atan2(d.x);
        let f = (ang + std::f64::consts::PI) / std::f64::consts::TAU * BINS as f64 - 0.5;
        let i0 = f.floor();
        let t = f - i0;
        let i0 = (i0 as i64).rem_euclid(BINS as i64) as usize;
        let i1 = (i0 + 1) % BINS;
        let rad = self.radius[i0] + t * (self.radius[i1] - self.radius[i0]);
        let hgt = self.height[i0] + t * (self.height[i1] - self.height[i0]);
        let c = if r > 1e-9 {
            (d / r).dot(self.distal)
        } else {
            0.0
        };
        let slope = 0.3 + 1.2 * (1.0 - c * c);
        hgt - slope * (r - rad).max(0.0)
    }
}

/// The gingiva height field, tabulated on a horizontal grid.
#[derive(Clone, Debug)]
pub struct Gingiva {
    origin: DVec2,
    h: f64,
    nx: usize,
    ny: usize,
    heights: Vec<f64>,
    /// Occlusal direction (unit, ±Z).
    pub occ: DVec3,
}

impl Gingiva {
    /// Tabulates the smooth maximum of the teeth's terms over the box `[lo, hi]`.
    pub fn new(
        teeth: &[MarginPolar],
        lo: DVec2,
        hi: DVec2,
        h: f64,
        occ: DVec3,
        floor: f64,
    ) -> Gingiva {
        let nx = ((hi.x - lo.x) / h).ceil() as usize + 2;
        let ny = ((hi.y - lo.y) / h).ceil() as usize + 2;
        let mut heights = vec![floor; nx * ny];
        let k = 0.35;
        for j in 0..ny {
            for i in 0..nx {
                let q = lo + DVec2::new(i as f64, j as f64) * h;
                let terms: Vec<f64> = teeth
                    .iter()
                    .map(|t| t.term(q))
                    .filter(|v| v.is_finite())
                    .collect();
                let m = terms.iter().cloned().fold(floor, f64::max);
                let s: f64 = terms.iter().map(|v| ((v - m) / k).exp()).sum::<f64>()
                    + ((floor - m) / k).exp();
                heights[i + nx * j] = m + k * s.ln();
            }
        }
        Gingiva {
            origin: lo,
            h,
            nx,
            ny,
            heights,
            occ,
        }
    }

    /// Gingiva height (along `occ`) at horizontal point `q` (bilinear).
    pub fn height(&self, q: DVec2) -> f64 {
        let f = (q - self.origin) / self.h;
        let i = (f.x.floor().max(0.0) as usize).min(self.nx - 2);
        let j = (f.y.floor().max(0.0) as usize).min(self.ny - 2);
        let tx = (f.x - i as f64).clamp(0.0, 1.0);
        let ty = (f.y - j as f64).clamp(0.0, 1.0);
        let v = |a: usize, b: usize| self.heights[a + self.nx * b];
        let a = v(i, j) + tx * (v(i + 1, j) - v(i, j));
        let b = v(i, j + 1) + tx * (v(i + 1, j + 1) - v(i, j + 1));
        a + ty * (b - a)
    }

    /// Implicit value of the gingiva solid at `p` (negative below the gum surface).
    pub fn eval(&self, p: DVec3) -> f64 {
        p.dot(self.occ) - self.height(DVec2::new(p.x, p.y))
    }
}
