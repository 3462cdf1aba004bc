//! Parametrisation of the band as an annulus: a turn parameter `φ` around the tooth (arc length
//! of the IOS margin, the CBCT loop aligned to it by angle) × a height fraction `v` (0 on the
//! CBCT loop, 1 on the IOS margin); and the Hermite "loft" that lifts `(φ, v)` to 3D with the
//! tangents of both surfaces, so the band meets crown and root smoothly.

use crate::cut::ToothFrame;
use crate::{Error, Result};
use glam::DVec3;

/// One loop with its turn parameter: positions, outward surface directions and increasing `φ`
/// (in turns; `phi[0] ≤ φ < phi[0] + 1`).
#[derive(Clone, Debug)]
pub struct LoopParam {
    /// Positions, in the loop's (counter-clockwise about the axis) order.
    pub pts: Vec<DVec3>,
    /// Unit surface directions at each vertex (see [`super::BandLoops`]).
    pub dirs: Vec<DVec3>,
    /// Strictly increasing turn parameter per vertex.
    pub phi: Vec<f64>,
    /// Polyline length.
    pub length: f64,
}

fn wrap_half(x: f64) -> f64 {
    x - crate::geom::round(x)
}

/// Unwrapped angle sequence (radians) along a closed loop and its total winding.
fn unwrapped_angles(frame: &ToothFrame, pts: &[DVec3]) -> (Vec<f64>, f64) {
    let tau = std::f64::consts::TAU;
    let n = pts.len();
    let raw: Vec<f64> = pts.iter().map(|&p| frame.angle(p)).collect();
    let mut out = Vec::with_capacity(n);
    out.push(raw[0]);
    for i in 1..n {
        let d = tau * wrap_half((raw[i] - raw[i - 1]) / tau);
        out.push(out[i - 1] + d);
    }
    let closing = tau * wrap_half((raw[0] - raw[n - 1]) / tau);
    let total = out[n - 1] + closing - out[0];
    (out, total)
}

/// Winding of a closed loop about the frame axis, in turns (≈ ±1 for a loop around the tooth).
pub fn winding(frame: &ToothFrame, pts: &[DVec3]) -> f64 {
    unwrapped_angles(frame, pts).1 / std::f64::consts::TAU
}

/// Whether a closed loop with winding `w` (see [`winding`]) goes once around the tooth axis:
/// `Some(true)` counter-clockwise, `Some(false)` clockwise, `None` otherwise.
pub fn once_around(w: f64) -> Option<bool> {
    if (w - 1.0).abs() < 0.5 {
        Some(true)
    } else if (w + 1.0).abs() < 0.5 {
        Some(false)
    } else {
        None
    }
}

fn cumulative_length(pts: &[DVec3]) -> (Vec<f64>, f64) {
    let mut c = Vec::with_capacity(pts.len());
    let mut s = 0.0;
    for i in 0..pts.len() {
        c.push(s);
        s += (pts[(i + 1) % pts.len()] - pts[i]).length();
    }
    (c, s)
}

impl LoopParam {
    /// The upper (IOS margin) loop: `φ` is its normalised arc length from vertex 0.
    pub fn upper(pts: Vec<DVec3>, dirs: Vec<DVec3>) -> Result<LoopParam> {
        let (c, length) = cumulative_length(&pts);
        if length.is_nan() || length <= 0.0 {
            return Err(Error::InvalidArgument("margin loop has zero length".into()));
        }
        let phi: Vec<f64> = c.iter().map(|s| s / length).collect();
        if phi.windows(2).any(|w| w[1] <= w[0]) {
            return Err(Error::InvalidArgument(
                "margin loop repeats a position".into(),
            ));
        }
        Ok(Self {
            pts,
            dirs,
            phi,
            length,
        })
    }

    /// The lower (CBCT cut) loop, aligned to `upper` by angle about the axis: `φ` follows the
    /// upper loop's parameter at the same angle, smoothed and blended with arc length until
    /// strictly increasing.
    pub fn lower_aligned(
        pts: Vec<DVec3>,
        dirs: Vec<DVec3>,
        upper: &LoopParam,
        frame: &ToothFrame,
    ) -> Result<LoopParam> {
        let n = pts.len();
        let (c, length) = cumulative_length(&pts);
        if length.is_nan() || length <= 0.0 || n < 3 {
            return Err(Error::InvalidArgument("cut loop is degenerate".into()));
        }
        // Upper: monotone table angle → φ.
        let (ua, _) = unwrapped_angles(frame, &upper.pts);
        let mut table: Vec<(f64, f64)> = Vec::with_capacity(ua.len() + 1);
        let mut m = f64::NEG_INFINITY;
        for (i, &a) in ua.iter().enumerate() {
            m = m.max(a);
            table.push((m, upper.phi[i]));
        }
        table.push((ua[0] + std::f64::consts::TAU, 1.0));
        let phi_at = |a: f64| {
            let a0 = table[0].0;
            let x = a0 + (a - a0).rem_euclid(std::f64::consts::TAU);
            let k = table
                .partition_point(|&(t, _)| t <= x)
                .clamp(1, table.len() - 1);
            let (t0, p0) = table[k - 1];
            let (t1, p1) = table[k];
            if t1 > t0 {
                p0 + (p1 - p0) * ((x - t0) / (t1 - t0)).clamp(0.0, 1.0)
            } else {
                p0
            }
        };
        let arc: Vec<f64> = c.iter().map(|s| s / length).collect();
        let raw: Vec<f64> = pts.iter().map(|&p| phi_at(frame.angle(p))).collect();
        let r0 = raw[0];
        let d: Vec<f64> = (0..n)
            .map(|j| r0 + wrap_half(raw[j] - arc[j] - r0))
            .collect();
        let mut w = (n / 40).max(1);
        loop {
            let phi: Vec<f64> = if w >= n {
                let mean = d.iter().sum::<f64>() / n as f64;
                arc.iter().map(|a| a + mean).collect()
            } else {
                (0..n)
                    .map(|j| {
                        let s: f64 = (0..=2 * w)
                            .map(|k| {
                                let i = (j + n + k - w) % n;
                                // Keep the circular neighbourhood continuous in d.
                                d[j] + wrap_half(d[i] - d[j])
                            })
                            .sum();
                        arc[j] + s / (2 * w + 1) as f64
                    })
                    .collect()
            };
            let ok = phi.windows(2).all(|x| x[1] > x[0]) && phi[0] + 1.0 > phi[n - 1];
            if ok {
                return Ok(Self {
                    pts,
                    dirs,
                    phi,
                    length,
                });
            }
            if w >= n {
                return Err(Error::InvalidArgument(
                    "cut loop cannot be parametrised".into(),
                ));
            }
            w *= 2;
        }
    }

    /// Position and direction at turn parameter `x` (any real; periodic).
    pub fn eval(&self, x: f64) -> (DVec3, DVec3) {
        let n = self.pts.len();
        let p0 = self.phi[0];
        let x = p0 + (x - p0).rem_euclid(1.0);
        let k = self.phi.partition_point(|&p| p <= x);
        let (i, j, a, b) = if k >= n {
            (n - 1, 0, self.phi[n - 1], self.phi[0] + 1.0)
        } else {
            (k - 1, k, self.phi[k - 1], self.phi[k])
        };
        let t = if b > a {
            ((x - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (
            self.pts[i].lerp(self.pts[j], t),
            self.dirs[i].lerp(self.dirs[j], t),
        )
    }
}

/// The band surface between the two loops.
#[derive(Clone, Debug)]
pub struct Loft {
    /// IOS margin (v = 1).
    pub upper: LoopParam,
    /// CBCT cut loop (v = 0).
    pub lower: LoopParam,
    /// Tangent length as a fraction of the loop-to-loop distance (0: straight ruled band).
    pub tangent_scale: f64,
    /// Mean loop-to-loop distance.
    pub mean_height: f64,
    /// Mean loop length.
    pub mean_length: f64,
}

impl Loft {
    /// Builds the loft and its mean dimensions.
    pub fn new(upper: LoopParam, lower: LoopParam, tangent_scale: f64) -> Loft {
        let samples = 128;
        let mean_height = (0..samples)
            .map(|i| {
                let x = i as f64 / samples as f64;
                (upper.eval(x).0 - lower.eval(x).0).length()
            })
            .sum::<f64>()
            / samples as f64;
        let mean_length = 0.5 * (upper.length + lower.length);
        Self {
            upper,
            lower,
            tangent_scale,
            mean_height,
            mean_length,
        }
    }

    /// Cubic Hermite between the lower point (v = 0, leaving along the root's direction) and
    /// the upper point (v = 1, arriving along the crown's direction).
    pub fn point(&self, phi: f64, v: f64) -> DVec3 {
        let (a, da) = self.upper.eval(phi);
        let (b, db) = self.lower.eval(phi);
        let d = (a - b).length() * self.tangent_scale;
        let (v2, v3) = (v * v, v * v * v);
        let h00 = 2.0 * v3 - 3.0 * v2 + 1.0;
        let h10 = v3 - 2.0 * v2 + v;
        let h01 = -2.0 * v3 + 3.0 * v2;
        let h11 = v3 - v2;
        b * h00 + db * (d * h10) + a * h01 + da * (d * h11)
    }

    /// The planar annulus coordinates of `(φ, v)`: log-polar, conformal for a cylinder of the
    /// band's mean size, so planar Delaunay triangles stay well shaped in 3D.
    pub fn plane(&self, phi: f64, v: f64) -> [f64; 2] {
        let r = (std::f64::consts::TAU * v * self.mean_height / self.mean_length).exp();
        let a = std::f64::consts::TAU * phi;
        [r * a.cos(), r * a.sin()]
    }
}
