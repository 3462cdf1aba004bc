//! Placement of the teeth on a dental arch (world frame: x to the patient's left, y anterior,
//! z up; occlusal plane near z = 0) with realistic angulation (tip), inclination (torque) and
//! nearly touching neighbours; and each placed tooth's gingival margin.

use super::rng::Rng;
use super::shape::ToothShape;
use crate::arch::{Jaw, ToothType, tooth_type};
use glam::{DMat3, DVec3};

/// A parabolic arch `y = depth·(1 − (x/half_width)²)` parameterised by arc length from the
/// midline (s > 0 on the patient's left).
#[derive(Clone, Debug)]
pub struct Arch {
    xs: Vec<f64>,
    ss: Vec<f64>,
    half_width: f64,
    depth: f64,
}

impl Arch {
    /// The arch of a jaw (the upper one wider than the lower), scaled by `scale`.
    pub fn new(jaw: Jaw, scale: f64) -> Arch {
        let (w, d) = match jaw {
            Jaw::Upper => (29.5 * scale, 45.0 * scale),
            Jaw::Lower => (26.0 * scale, 42.0 * scale),
        };
        let n = 4000;
        let xmax = 1.6 * w;
        let mut xs = Vec::with_capacity(n + 1);
        let mut ss = Vec::with_capacity(n + 1);
        let mut s = 0.0;
        for i in 0..=n {
            let x = xmax * i as f64 / n as f64;
            if i > 0 {
                let xm = x - 0.5 * xmax / n as f64;
                let dy = -2.0 * d * xm / (w * w);
                s += (1.0 + dy * dy).sqrt() * xmax / n as f64;
            }
            xs.push(x);
            ss.push(s);
        }
        Arch {
            xs,
            ss,
            half_width: w,
            depth: d,
        }
    }

    fn x_of(&self, s: f64) -> f64 {
        let a = s.abs();
        let i = self
            .ss
            .partition_point(|&v| v < a)
            .clamp(1, self.ss.len() - 1);
        let t = (a - self.ss[i - 1]) / (self.ss[i] - self.ss[i - 1]);
        let x = self.xs[i - 1] + t * (self.xs[i] - self.xs[i - 1]);
        if s < 0.0 { -x } else { x }
    }

    /// Point at arc length `s` (z = 0).
    pub fn point(&self, s: f64) -> DVec3 {
        let x = self.x_of(s);
        DVec3::new(x, self.depth * (1.0 - (x / self.half_width).powi(2)), 0.0)
    }

    /// Unit tangent at `s`, pointing away from the midline (distally).
    pub fn distal(&self, s: f64) -> DVec3 {
        let x = self.x_of(s);
        let dy = -2.0 * self.depth * x / (self.half_width * self.half_width);
        let t = DVec3::new(1.0, dy, 0.0).normalize();
        if s < 0.0 { -t } else { t }
    }

    /// Unit outward (buccal) horizontal normal at `s`.
    pub fn buccal(&self, s: f64) -> DVec3 {
        let x = self.x_of(s);
        let dy = -2.0 * self.depth * x / (self.half_width * self.half_width);
        DVec3::new(-dy, 1.0, 0.0).normalize()
    }
}

/// A tooth placed in the world: `world = rot · local + center` (`rot` orthogonal; a reflection
/// on one side of the arch so both sides use the same anatomical local frame).
#[derive(Clone, Debug)]
pub struct PlacedTooth {
    /// The shape.
    pub shape: ToothShape,
    /// Local → world linear part (orthogonal, det ±1).
    pub rot: DMat3,
    /// World position of the local origin (CEJ centre).
    pub center: DVec3,
    /// Arc-length position of the crown centre on the arch.
    pub s: f64,
    /// Local margin heights: base and interproximal rise and a small random wave.
    margin_base: f64,
    margin_rise: f64,
    margin_wave: (f64, f64),
}

impl PlacedTooth {
    /// A tooth at a given pose with its margin parameters (local base height, interproximal
    /// rise, (wave amplitude, wave phase)).
    pub fn new(
        shape: ToothShape,
        rot: DMat3,
        center: DVec3,
        s: f64,
        margin: (f64, f64, (f64, f64)),
    ) -> PlacedTooth {
        PlacedTooth {
            shape,
            rot,
            center,
            s,
            margin_base: margin.0,
            margin_rise: margin.1,
            margin_wave: margin.2,
        }
    }

    /// World → local.
    #[inline]
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        self.rot.transpose() * (p - self.center)
    }

    /// Local → world.
    #[inline]
    pub fn to_world(&self, l: DVec3) -> DVec3 {
        self.rot * l + self.center
    }

    /// The same tooth moved by a rigid transform.
    pub fn moved(&self, t: &crate::Rigid) -> PlacedTooth {
        PlacedTooth {
            rot: t.rot * self.rot,
            center: t.apply(self.center),
            ..self.clone()
        }
    }

    /// Crown centre (on the long axis at the height of contour), world.
    pub fn crown_center(&self) -> DVec3 {
        self.to_world(DVec3::new(0.0, 0.0, self.shape.z_widest))
    }

    /// Implicit value at a world point.
    #[inline]
    pub fn eval(&self, p: DVec3) -> f64 {
        self.shape.eval(self.to_local(p))
    }

    /// Unit long axis (apex → occlusal), world.
    pub fn axis(&self) -> DVec3 {
        (self.rot * DVec3::Z).normalize()
    }

    /// World bounding box of the tooth.
    pub fn world_box(&self) -> (DVec3, DVec3) {
        let (lo, hi) = self.shape.local_box();
        let mut blo = DVec3::splat(f64::INFINITY);
        let mut bhi = DVec3::splat(f64::NEG_INFINITY);
        for c in 0..8 {
            let l = DVec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            let w = self.to_world(l);
            blo = blo.min(w);
            bhi = bhi.max(w);
        }
        (blo, bhi)
    }

    /// Local margin height at angle `phi` around the long axis (0 = distal).
    pub fn margin_height(&self, phi: f64) -> f64 {
        let c = phi.cos();
        self.margin_base
            + self.margin_rise * c * c
            + self.margin_wave.0 * (phi + self.margin_wave.1).sin()
    }

    /// The point of the tooth surface at local height `z` in direction `phi` from the long
    /// axis (bisection along the ray), world frame.
    pub fn surface_point(&self, phi: f64, z: f64) -> DVec3 {
        let dir = DVec3::new(phi.cos(), phi.sin(), 0.0);
        let (mut lo, mut hi) = (0.0, self.shape.md.max(self.shape.bl));
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if self.shape.eval(DVec3::new(0.0, 0.0, z) + dir * mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.to_world(DVec3::new(0.0, 0.0, z) + dir * (0.5 * (lo + hi)))
    }

    /// The nominal gingival margin: `n` points on the tooth surface at the margin height,
    /// ordered by angle, world frame.
    pub fn margin(&self, n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|j| {
                let phi = std::f64::consts::TAU * j as f64 / n as f64;
                self.surface_point(phi, self.margin_height(phi))
            })
            .collect()
    }

    /// The gingival margin where a gum surface `gum` (negative below it) actually meets the
    /// tooth: per angle, the height on the tooth surface where `gum` changes sign (searched
    /// within ±3 mm of the nominal margin; the nominal point where it does not).
    pub fn margin_against(&self, n: usize, gum: &dyn Fn(DVec3) -> f64) -> Vec<DVec3> {
        (0..n)
            .map(|j| {
                let phi = std::f64::consts::TAU * j as f64 / n as f64;
                let m = self.margin_height(phi);
                let (mut lo, mut hi) = (m - 3.0, m + 3.0);
                if gum(self.surface_point(phi, lo)) >= 0.0
                    || gum(self.surface_point(phi, hi)) <= 0.0
                {
                    return self.surface_point(phi, m);
                }
                for _ in 0..30 {
                    let mid = 0.5 * (lo + hi);
                    if gum(self.surface_point(phi, mid)) < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                self.surface_point(phi, 0.5 * (lo + hi))
            })
            .collect()
    }
}

/// (torque, tip) in degrees per tooth type and jaw.
fn tilts(jaw: Jaw, fdi: u8) -> (f64, f64) {
    match (jaw, tooth_type(fdi), fdi % 10) {
        (Jaw::Upper, ToothType::Incisor, 1) => (15.0, 5.0),
        (Jaw::Upper, ToothType::Incisor, _) => (10.0, 8.0),
        (Jaw::Upper, ToothType::Canine, _) => (4.0, 9.0),
        (Jaw::Upper, ToothType::Premolar, _) => (-6.0, 3.0),
        (Jaw::Upper, ToothType::Molar, _) => (-9.0, 3.0),
        (Jaw::Lower, ToothType::Incisor, _) => (6.0, 2.0),
        (Jaw::Lower, ToothType::Canine, _) => (0.0, 5.0),
        (Jaw::Lower, ToothType::Premolar, _) => (-10.0, 2.0),
        (Jaw::Lower, ToothType::Molar, _) => (-16.0, 2.0),
    }
}

/// The 14 FDI numbers of a jaw (no third molars) in arch order, right distal end first.
pub fn jaw_teeth(jaw: Jaw) -> Vec<u8> {
    let (r, l) = match jaw {
        Jaw::Upper => (10u8, 20u8),
        Jaw::Lower => (40u8, 30u8),
    };
    let mut v: Vec<u8> = (1..=7).rev().map(|p| r + p).collect();
    v.extend((1..=7).map(|p| l + p));
    v
}

fn place(
    shape: ToothShape,
    arch: &Arch,
    s: f64,
    jaw: Jaw,
    extra: (f64, f64, f64),
    margin: (f64, f64, (f64, f64)),
) -> PlacedTooth {
    let occ = if jaw == Jaw::Upper {
        -DVec3::Z
    } else {
        DVec3::Z
    };
    let frame = DMat3::from_cols(arch.distal(s), arch.buccal(s), occ);
    let (torque, tip) = tilts(jaw, shape.fdi);
    let r = frame
        * DMat3::from_rotation_y(-(tip + extra.1).to_radians())
        * DMat3::from_rotation_x(-(torque + extra.0).to_radians())
        * DMat3::from_rotation_z(extra.2.to_radians());
    // The crown's height-of-contour centre sits on the arch curve.
    let anchor = DVec3::new(0.0, 0.0, shape.z_widest);
    let center = arch.point(s) - r * anchor;
    PlacedTooth {
        shape,
        rot: r,
        center,
        s,
        margin_base: margin.0,
        margin_rise: margin.1,
        margin_wave: margin.2,
    }
}

/// Gap (mm, negative = overlap) between two teeth along rays parallel to the line joining their
/// crowns, and the contact point (midway across the smallest gap).
pub fn contact(a: &PlacedTooth, b: &PlacedTooth) -> (f64, DVec3) {
    let ca = a.to_world(DVec3::new(0.0, 0.0, a.shape.z_widest));
    let cb = b.to_world(DVec3::new(0.0, 0.0, b.shape.z_widest));
    let mut d = cb - ca;
    d.z = 0.0;
    let d = d.normalize();
    let up = DVec3::Z;
    let side = up.cross(d).normalize();
    let mid = 0.5 * (ca + cb);
    let reach = 0.5 * (cb - ca).length() + 6.0;
    let mut best = (f64::INFINITY, mid);
    for iv in -3..=3 {
        for ih in -2..=2 {
            let o = mid + up * (iv as f64 * 0.8) + side * (ih as f64 * 0.8);
            let fa = |t: f64| a.eval(o + d * t);
            let fb = |t: f64| b.eval(o + d * t);
            if fa(-reach) >= 0.0 || fb(reach) >= 0.0 || fa(reach) <= 0.0 || fb(-reach) <= 0.0 {
                continue;
            }
            let bis = |f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64| {
                // f(lo) < 0 (inside), f(hi) > 0.
                for _ in 0..40 {
                    let m = 0.5 * (lo + hi);
                    if f(m) < 0.0 { lo = m } else { hi = m }
                }
                0.5 * (lo + hi)
            };
            let ta = bis(&fa, -reach, reach);
            let tb = bis(&fb, reach, -reach);
            let g = tb - ta;
            if g < best.0 {
                best = (g, o + d * (0.5 * (ta + tb)));
            }
        }
    }
    best
}

/// Places every tooth of `teeth` (FDI numbers of one jaw, positions 1–7) on the arch, each
/// side from the midline outwards, with neighbour gaps of 0.05–0.15 mm at the contacts.
pub fn layout(jaw: Jaw, teeth: &[u8], rng: &mut Rng) -> Vec<PlacedTooth> {
    let arch = Arch::new(jaw, rng.range(0.95, 1.05));
    let mut placed: Vec<PlacedTooth> = Vec::new();
    // Shapes and random tilts, drawn in a fixed order (all 14 positions) for stability.
    let mut proto = Vec::new();
    for &fdi in &jaw_teeth(jaw) {
        let mut tr = rng.fork(fdi as u64);
        let shape = ToothShape::new(fdi, &mut tr);
        let extra = (
            tr.normal_clamped(2.0) * 1.5,
            tr.normal_clamped(2.0) * 1.5,
            tr.normal_clamped(2.0) * 2.0,
        );
        let zw = shape.z_widest;
        let margin = (
            zw - tr.range(1.3, 1.9),
            tr.range(1.0, 1.4),
            (tr.range(0.05, 0.15), tr.range(0.0, std::f64::consts::TAU)),
        );
        let gap = tr.range(0.05, 0.15);
        proto.push((fdi, shape, extra, margin, gap));
    }
    let get = |fdi: u8| proto.iter().find(|p| p.0 == fdi).cloned();
    let quads = match jaw {
        Jaw::Upper => (20u8, 10u8),
        Jaw::Lower => (30u8, 40u8),
    };
    // Centrals first, moved symmetrically until their mutual gap is right.
    let (Some(cl), Some(cr)) = (get(quads.0 + 1), get(quads.1 + 1)) else {
        return placed;
    };
    let gap0 = cl.4;
    let (mut sl, mut sr) = (gap0 / 2.0 + cl.1.md / 2.0, -(gap0 / 2.0 + cr.1.md / 2.0));
    let mut tl = place(cl.1.clone(), &arch, sl, jaw, cl.2, cl.3);
    let mut tr = place(cr.1.clone(), &arch, sr, jaw, cr.2, cr.3);
    for _ in 0..5 {
        let (g, _) = contact(&tr, &tl);
        if !g.is_finite() || (g - gap0).abs() < 0.005 {
            break;
        }
        sl -= 0.5 * (g - gap0);
        sr += 0.5 * (g - gap0);
        tl = place(cl.1.clone(), &arch, sl, jaw, cl.2, cl.3);
        tr = place(cr.1.clone(), &arch, sr, jaw, cr.2, cr.3);
    }
    for (side, q, central) in [(1.0f64, quads.0, tl), (-1.0, quads.1, tr)] {
        let mut prev = central.clone();
        placed.push(central);
        for pos in 2..=7u8 {
            let Some((_, shape, extra, margin, gap)) = get(q + pos) else {
                continue;
            };
            let mut s = side * (prev.s.abs() + prev.shape.md / 2.0 + gap + shape.md / 2.0);
            let mut t = place(shape.clone(), &arch, s, jaw, extra, margin);
            for _ in 0..5 {
                let (g, _) = contact(&prev, &t);
                if !g.is_finite() || (g - gap).abs() < 0.005 {
                    break;
                }
                s -= side * (g - gap);
                t = place(shape.clone(), &arch, s, jaw, extra, margin);
            }
            prev = t.clone();
            placed.push(t);
        }
    }
    placed.sort_by_key(|t| crate::arch::arch_position(t.shape.fdi));
    placed.retain(|t| teeth.contains(&t.shape.fdi));
    placed
}
