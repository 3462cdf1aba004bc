//! Parametric tooth shapes as implicit functions (negative inside, roughly a signed distance in
//! mm) in the tooth's local anatomical frame: x distal, y buccal/labial, z occlusal (long axis),
//! z = 0 at the cemento-enamel junction.
//!
//! Crown: a superellipse cross-section whose half-widths follow a cervical-constriction /
//! height-of-contour / occlusal-table profile, capped by an occlusal height field with Gaussian
//! cusps and fissure grooves, edges rounded by a smooth maximum. Roots: 1–3 tapered elliptic
//! capsules along straight, slightly distally curved axes, joined by smooth unions
//! (Quílez's polynomial smooth min).

use super::rng::Rng;
use crate::arch::{Jaw, ToothType, jaw_of, tooth_type};
use glam::DVec3;

/// Polynomial smooth minimum with blend radius `k` (mm).
#[inline]
pub fn smin(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// Polynomial smooth maximum with blend radius `k`.
#[inline]
pub fn smax(a: f64, b: f64, k: f64) -> f64 {
    -smin(-a, -b, k)
}

/// One cusp: a Gaussian bump of the occlusal surface.
#[derive(Clone, Debug)]
struct Cusp {
    x: f64,
    y: f64,
    height: f64,
    radius: f64,
}

/// One fissure: a Gaussian groove along a segment of the occlusal surface.
#[derive(Clone, Debug)]
struct Groove {
    a: (f64, f64),
    b: (f64, f64),
    depth: f64,
    width: f64,
}

/// One root: tapered elliptic capsule from `top` (z = 1) to `apex`.
#[derive(Clone, Debug)]
struct Root {
    top: DVec3,
    apex: DVec3,
    r_top: f64,
    r_apex: f64,
    /// Cross-section aspect (y half-axis / x half-axis).
    aspect: f64,
}

/// A parametric tooth.
#[derive(Clone, Debug)]
pub struct ToothShape {
    /// FDI number.
    pub fdi: u8,
    /// Mesiodistal crown width at the height of contour (mm).
    pub md: f64,
    /// Buccolingual crown width (mm).
    pub bl: f64,
    /// Crown height from the CEJ to the highest cusp (mm).
    pub crown_height: f64,
    /// Root length from the CEJ to the apex (mm).
    pub root_length: f64,
    /// Height of contour (widest part) above the CEJ (mm).
    pub z_widest: f64,
    exponent: f64,
    cervical: f64,
    occl_md: f64,
    occl_bl: f64,
    table: f64,
    edge_round: f64,
    occlusal_min: f64,
    incisal: bool,
    sampled: Option<Box<super::real::SampledSdf>>,
    cusps: Vec<Cusp>,
    grooves: Vec<Groove>,
    roots: Vec<Root>,
}

/// Nominal (MD width, BL width, crown height, root length) per jaw and tooth position 1–7.
fn nominal(jaw: Jaw, pos: u8) -> (f64, f64, f64, f64) {
    let upper = [
        (8.6, 7.0, 10.5, 13.0),
        (6.6, 6.0, 9.0, 13.0),
        (7.6, 8.0, 10.0, 16.5),
        (7.0, 9.0, 8.5, 14.0),
        (6.6, 9.0, 7.8, 14.0),
        (10.2, 11.0, 7.5, 13.0),
        (9.2, 10.8, 7.0, 12.5),
    ];
    let lower = [
        (5.5, 6.0, 9.0, 12.5),
        (5.9, 6.3, 9.5, 13.5),
        (6.9, 7.7, 11.0, 16.0),
        (7.0, 7.7, 8.5, 14.0),
        (7.1, 8.1, 8.0, 14.5),
        (10.5, 10.2, 7.5, 14.0),
        (10.0, 9.8, 7.0, 13.0),
    ];
    let i = (pos.clamp(1, 7) - 1) as usize;
    match jaw {
        Jaw::Upper => upper[i],
        Jaw::Lower => lower[i],
    }
}

impl ToothShape {
    /// A tooth of FDI number `fdi` (positions 1–7), sizes varied by a few percent.
    pub fn new(fdi: u8, rng: &mut Rng) -> ToothShape {
        let jaw = jaw_of(fdi);
        let pos = fdi % 10;
        let ty = tooth_type(fdi);
        let (md0, bl0, hc0, rl0) = nominal(jaw, pos);
        let md = (md0 * rng.range(0.96, 1.04)).clamp(5.5, 10.5);
        let bl = bl0 * rng.range(0.96, 1.04);
        let crown_height = hc0 * rng.range(0.95, 1.05);
        let root_length = (rl0 * rng.range(0.95, 1.05)).clamp(12.0, 17.0);
        let (a, b) = (md / 2.0, bl / 2.0);
        let z_widest = match ty {
            ToothType::Incisor => 0.40 * crown_height,
            ToothType::Canine => 0.42 * crown_height,
            _ => 0.36 * crown_height,
        };
        let CrownForm {
            exponent,
            cervical,
            occl_md,
            occl_bl,
            table,
            edge_round,
            incisal,
            cusps,
            grooves,
        } = crown_form(ty, jaw, crown_height, (a, b), rng);
        // Roots.
        let (ca, cb) = (a * cervical, b * cervical);
        let distal_curve = rng.range(0.4, 1.2);
        let roots = roots(ty, jaw, pos, (ca, cb), root_length, distal_curve);
        ToothShape {
            fdi,
            md,
            bl,
            crown_height,
            root_length,
            z_widest,
            exponent,
            cervical,
            occl_md,
            occl_bl,
            table,
            edge_round,
            occlusal_min: table
                - grooves.iter().map(|g| g.depth).sum::<f64>()
                - if incisal { 0.8 * 1.7 } else { 0.0 },
            incisal,
            sampled: None,
            cusps,
            grooves,
            roots,
        }
    }

    /// A real tooth given by a sampled signed distance in its local frame, with its measures.
    pub fn from_sampled(
        fdi: u8,
        sdf: super::real::SampledSdf,
        md: f64,
        bl: f64,
        crown_height: f64,
        root_length: f64,
        z_widest: f64,
    ) -> ToothShape {
        ToothShape {
            fdi,
            md,
            bl,
            crown_height,
            root_length,
            z_widest,
            exponent: 2.0,
            cervical: 1.0,
            occl_md: 1.0,
            occl_bl: 1.0,
            table: crown_height,
            edge_round: 0.5,
            occlusal_min: crown_height,
            incisal: false,
            sampled: Some(Box::new(sdf)),
            cusps: Vec::new(),
            grooves: Vec::new(),
            roots: Vec::new(),
        }
    }

    /// Local bounding box (lo, hi) enclosing the surface with a margin.
    pub fn local_box(&self) -> (DVec3, DVec3) {
        if let Some(s) = &self.sampled {
            return s.bounds();
        }
        let (a, b) = (self.md / 2.0, self.bl / 2.0);
        let mut lo = DVec3::new(-a - 0.5, -b - 0.5, -self.root_length - 1.0);
        let mut hi = DVec3::new(a + 0.5, b + 0.5, self.crown_height + 0.8);
        for r in &self.roots {
            let m = r.r_top * r.aspect.max(1.0) + 0.5;
            lo = lo
                .min(r.apex - DVec3::splat(m))
                .min(r.top - DVec3::splat(m));
            hi = hi
                .max(r.apex + DVec3::splat(m))
                .max(r.top + DVec3::splat(m));
        }
        (lo, hi)
    }

    /// Profile scale of the crown cross-section at height `z` for a half-width whose
    /// cervical/occlusal ratios are `c0`/`c1`.
    #[inline]
    fn profile(&self, z: f64, c0: f64, c1: f64) -> f64 {
        let zw = self.z_widest;
        if z <= 0.0 {
            c0
        } else if z < zw {
            let u = (zw - z) / zw;
            1.0 - (1.0 - c0) * u * u
        } else {
            let u = ((z - zw) / (self.table.max(zw + 0.5) - zw)).min(1.3);
            1.0 - (1.0 - c1) * u * u
        }
    }

    /// Occlusal surface height above the CEJ at (x, y).
    #[inline]
    fn occlusal(&self, x: f64, y: f64) -> f64 {
        let mut t = self.table;
        let a = self.md / 2.0;
        if self.incisal {
            // Incisal edge slightly lower at the corners.
            t -= 0.8 * (x / a).powi(2).min(1.7);
        }
        for c in &self.cusps {
            let d2 = (x - c.x).powi(2) + (y - c.y).powi(2);
            let e = d2 / (2.0 * c.radius * c.radius);
            if e < 14.0 {
                t += c.height * (-e).exp();
            }
        }
        for g in &self.grooves {
            let (dx, dy) = (g.b.0 - g.a.0, g.b.1 - g.a.1);
            let len2 = dx * dx + dy * dy;
            let s = (((x - g.a.0) * dx + (y - g.a.1) * dy) / len2).clamp(0.0, 1.0);
            let (px, py) = (g.a.0 + s * dx - x, g.a.1 + s * dy - y);
            let e = (px * px + py * py) / (2.0 * g.width * g.width);
            if e < 14.0 {
                t -= g.depth * (-e).exp();
            }
        }
        t
    }

    /// Crown solid (without roots).
    #[inline]
    fn crown(&self, p: DVec3) -> f64 {
        let (a0, b0) = (self.md / 2.0, self.bl / 2.0);
        let z = p.z;
        let a = a0 * self.profile(z, self.cervical, self.occl_md);
        let b = b0 * self.profile(z, self.cervical, self.occl_bl);
        let n = self.exponent;
        let u = (p.x / a).abs();
        let v = (p.y / b).abs();
        // Superellipse norm with one pow: max·(1 + (min/max)^n)^(1/n).
        let (hi, lo) = if u >= v { (u, v) } else { (v, u) };
        let norm = if hi > 0.0 {
            hi * (1.0 + (lo / hi).powf(n)).powf(1.0 / n)
        } else {
            0.0
        };
        let side = (norm - 1.0) * a.min(b);
        // Below the lowest possible occlusal surface by more than the edge rounding, the
        // occlusal term cannot change the smooth maximum: skip it.
        let top = if z - self.occlusal_min < side - self.edge_round {
            f64::NEG_INFINITY
        } else {
            z - self.occlusal(p.x, p.y)
        };
        let bottom = -z - 1.5;
        let crown = if top == f64::NEG_INFINITY {
            side
        } else {
            smax(side, top, self.edge_round)
        };
        smax(crown, bottom, 0.5)
    }

    /// Signed distance-like value of the whole tooth at local point `p` (negative inside).
    pub fn eval(&self, p: DVec3) -> f64 {
        if let Some(s) = &self.sampled {
            return s.eval(p);
        }
        let mut d = self.crown(p);
        for r in &self.roots {
            d = smin(d, root_sdf(r, p), 1.2);
        }
        d
    }
}

/// The crown's form of a tooth type: cross-section, occlusal table, cusps and grooves.
struct CrownForm {
    exponent: f64,
    cervical: f64,
    occl_md: f64,
    occl_bl: f64,
    table: f64,
    edge_round: f64,
    incisal: bool,
    cusps: Vec<Cusp>,
    grooves: Vec<Groove>,
}

/// The crown form of a tooth of type `ty` whose crown is `top` high and `(a, b)` half wide
/// (mesiodistal, buccolingual); molar cusp heights vary with `rng`.
fn crown_form(ty: ToothType, jaw: Jaw, top: f64, (a, b): (f64, f64), rng: &mut Rng) -> CrownForm {
    let mut cusps = Vec::new();
    let mut grooves = Vec::new();
    // Cross-section exponent, cervical and occlusal (mesiodistal, buccolingual) width ratios,
    // the occlusal table's drop below the crown's top, the edge rounding; incisal or not.
    let (exponent, cervical, occl_md, occl_bl, drop, edge_round, incisal) = match ty {
        ToothType::Incisor => (2.3, 0.70, 0.92, 0.22, 0.0, 0.6, true),
        ToothType::Canine => (2.2, 0.68, 0.80, 0.45, 2.2, 0.8, false),
        ToothType::Premolar => (2.4, 0.70, 0.82, 0.80, 2.0, 0.9, false),
        ToothType::Molar => (2.8, 0.74, 0.84, 0.80, 2.2, 1.0, false),
    };
    let table = top - drop;
    match ty {
        ToothType::Incisor => {
            // Mamelons: three tiny lobes on the incisal edge.
            for k in [-1.0, 0.0, 1.0] {
                cusps.push(Cusp {
                    x: k * 0.55 * a,
                    y: 0.0,
                    height: 0.15,
                    radius: 0.35 * a,
                });
            }
        }
        ToothType::Canine => {
            cusps.push(Cusp {
                x: -0.08 * a,
                y: 0.1 * b,
                height: 2.4,
                radius: 0.55 * a,
            });
        }
        ToothType::Premolar => {
            let lingual = if jaw == Jaw::Lower { 0.9 } else { 1.6 };
            cusps.push(Cusp {
                x: 0.0,
                y: 0.42 * b,
                height: 2.0,
                radius: 0.42 * a,
            });
            cusps.push(Cusp {
                x: 0.0,
                y: -0.45 * b,
                height: lingual,
                radius: 0.40 * a,
            });
            grooves.push(Groove {
                a: (-0.6 * a, 0.0),
                b: (0.6 * a, 0.0),
                depth: 0.7,
                width: 0.35,
            });
        }
        ToothType::Molar => {
            let pts: &[(f64, f64, f64)] = if jaw == Jaw::Upper {
                &[
                    (-0.45, 0.45, 2.0),
                    (0.45, 0.45, 1.8),
                    (-0.40, -0.45, 2.2),
                    (0.45, -0.50, 1.4),
                ]
            } else {
                &[
                    (-0.55, 0.45, 2.0),
                    (0.05, 0.50, 1.9),
                    (0.62, 0.30, 1.5),
                    (-0.45, -0.45, 2.2),
                    (0.40, -0.45, 2.1),
                ]
            };
            for &(x, y, h) in pts {
                cusps.push(Cusp {
                    x: x * a,
                    y: y * b,
                    height: h * rng.range(0.9, 1.1),
                    radius: 0.34 * a.min(b) * 1.2,
                });
            }
            grooves.push(Groove {
                a: (-0.75 * a, 0.0),
                b: (0.75 * a, 0.0),
                depth: 0.8,
                width: 0.35,
            });
            grooves.push(Groove {
                a: (-0.15 * a, 0.0),
                b: (-0.25 * a, 0.9 * b),
                depth: 0.6,
                width: 0.3,
            });
            grooves.push(Groove {
                a: (0.15 * a, 0.0),
                b: (0.25 * a, -0.9 * b),
                depth: 0.6,
                width: 0.3,
            });
        }
    }
    CrownForm {
        exponent,
        cervical,
        occl_md,
        occl_bl,
        table,
        edge_round,
        incisal,
        cusps,
        grooves,
    }
}

/// The roots of a tooth of type `ty` at arch position `pos`, cervical half widths `(ca, cb)`,
/// `l` long, their apices bent distally by `distal_curve`.
fn roots(
    ty: ToothType,
    jaw: Jaw,
    pos: u8,
    (ca, cb): (f64, f64),
    l: f64,
    distal_curve: f64,
) -> Vec<Root> {
    let mut roots = Vec::new();
    let mut root = |top: DVec3, apex: DVec3, r_top: f64, aspect: f64| {
        roots.push(Root {
            top,
            apex,
            r_top,
            r_apex: 0.45,
            aspect,
        })
    };
    let z0 = 1.0;
    match (ty, jaw) {
        (ToothType::Molar, Jaw::Upper) => {
            let r = 0.42 * ca.min(cb);
            root(
                DVec3::new(-0.45 * ca, 0.45 * cb, z0),
                DVec3::new(-0.6 * ca + distal_curve, 0.6 * cb, -l * 0.92),
                r,
                1.0,
            );
            root(
                DVec3::new(0.45 * ca, 0.45 * cb, z0),
                DVec3::new(0.7 * ca + distal_curve, 0.5 * cb, -l * 0.88),
                r,
                1.0,
            );
            root(
                DVec3::new(0.0, -0.45 * cb, z0),
                DVec3::new(distal_curve * 0.5, -0.9 * cb, -l),
                r * 1.15,
                1.0,
            );
        }
        (ToothType::Molar, Jaw::Lower) => {
            let r = 0.40 * ca;
            root(
                DVec3::new(-0.45 * ca, 0.0, z0),
                DVec3::new(-0.55 * ca + distal_curve, 0.0, -l),
                r,
                1.8,
            );
            root(
                DVec3::new(0.45 * ca, 0.0, z0),
                DVec3::new(0.55 * ca + distal_curve, 0.0, -l * 0.94),
                r,
                1.7,
            );
        }
        (ToothType::Premolar, Jaw::Upper) if pos == 4 => {
            let r = 0.45 * ca;
            root(
                DVec3::new(0.0, 0.4 * cb, z0),
                DVec3::new(distal_curve, 0.55 * cb, -l),
                r,
                1.1,
            );
            root(
                DVec3::new(0.0, -0.4 * cb, z0),
                DVec3::new(distal_curve, -0.55 * cb, -l * 0.95),
                r,
                1.1,
            );
        }
        _ => {
            let aspect = (cb / ca).clamp(0.8, 1.6);
            root(
                DVec3::new(0.0, 0.0, z0),
                DVec3::new(distal_curve, 0.0, -l),
                0.92 * ca.min(cb / aspect),
                aspect,
            );
        }
    }
    roots
}

fn root_sdf(r: &Root, p: DVec3) -> f64 {
    let axis = r.apex - r.top;
    let len2 = axis.length_squared();
    let t = ((p - r.top).dot(axis) / len2).clamp(0.0, 1.0);
    let c = r.top + axis * t;
    let rad = r.r_top + (r.r_apex - r.r_top) * t * t.sqrt();
    let mut d = p - c;
    d.y /= r.aspect;
    d.length() * (1.0f64).min(r.aspect) - rad
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_type_is_inside_at_core_and_outside_at_box() {
        let mut rng = Rng::new(3);
        for fdi in [11u8, 13, 14, 16, 17, 31, 33, 35, 36, 47] {
            let s = ToothShape::new(fdi, &mut rng);
            assert!(s.eval(DVec3::new(0.0, 0.0, 2.0)) < 0.0, "{fdi} crown core");
            assert!(s.eval(DVec3::new(0.0, 0.0, -s.root_length * 0.5)) < 0.0 || s.roots.len() > 1);
            let (lo, hi) = s.local_box();
            for p in [lo, hi, DVec3::new(lo.x, hi.y, lo.z)] {
                assert!(s.eval(p) > 0.0, "{fdi} box corner");
            }
            assert!((5.5..=10.5).contains(&s.md));
            assert!((12.0..=17.0).contains(&s.root_length));
        }
    }
}
