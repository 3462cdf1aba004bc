//! CBCT simulation: each tooth is imaged on a voxel grid aligned with the CBCT frame
//! (partial-volume occupancy, correlated noise, Gaussian blur), segmented at a threshold
//! (with a per-tooth bias that inflates or shrinks it), split from touching neighbours along a
//! plane (both get flattened at the contact), surfaced by surface nets and warped by a smooth
//! low-frequency distortion. A metal restoration bloats the crown and adds streak spikes.

use super::grid::Grid;
use super::layout::PlacedTooth;
use super::rng::Rng;
use super::surface_nets::extract_closed;
use crate::Rigid;
use crate::mesh::TriMesh;
use glam::DVec3;

/// How strongly the CBCT is degraded.
#[derive(Clone, Debug, PartialEq)]
pub struct CbctRealism {
    /// Voxel size (mm).
    pub voxel: f64,
    /// Gaussian blur sigma (mm).
    pub blur_sigma: f64,
    /// Standard deviation of the (pre-blur) voxel noise, in occupancy units.
    pub noise: f64,
    /// Maximum magnitude of the per-tooth segmentation bias (mm; + inflates).
    pub threshold_bias: f64,
    /// Amplitude of the smooth spatial distortion (mm).
    pub distortion: f64,
    /// Split touching neighbours along a plane (flattening both).
    pub contact_flattening: bool,
    /// Surface spacing of the output mesh (mm): the blurred volume is resampled trilinearly.
    pub mesh_spacing: f64,
}

impl Default for CbctRealism {
    fn default() -> Self {
        Self {
            voxel: 0.3,
            blur_sigma: 0.4,
            noise: 0.25,
            threshold_bias: 0.25,
            distortion: 0.25,
            contact_flattening: true,
            mesh_spacing: 0.3,
        }
    }
}

/// A smooth random displacement field (sum of three plane waves per axis).
#[derive(Clone, Debug)]
pub struct Distortion {
    waves: Vec<(DVec3, DVec3, f64)>,
}

impl Distortion {
    /// Random field of amplitude ~`amp` mm and wavelengths 15–40 mm.
    pub fn new(rng: &mut Rng, amp: f64) -> Distortion {
        let waves = (0..3)
            .map(|_| {
                let k = rng.unit_vector() * (std::f64::consts::TAU / rng.range(15.0, 40.0));
                let a = rng.unit_vector() * (amp * rng.range(0.5, 0.8));
                (k, a, rng.range(0.0, std::f64::consts::TAU))
            })
            .collect();
        Distortion { waves }
    }

    /// Displacement at `p`.
    pub fn at(&self, p: DVec3) -> DVec3 {
        self.waves.iter().fold(DVec3::ZERO, |acc, (k, a, ph)| {
            acc + *a * (k.dot(p) + ph).sin()
        })
    }
}

/// Metal artefact parameters of one tooth (in its local frame).
#[derive(Clone, Debug)]
pub struct Metal {
    bloat: f64,
    streaks: Vec<(f64, f64)>,
    z0: f64,
    z_mid: f64,
}

impl Metal {
    /// A restoration on the crown of `t`.
    pub fn new(t: &PlacedTooth, rng: &mut Rng) -> Metal {
        let streaks = (0..rng.below(3) + 5)
            .map(|_| (rng.range(0.0, std::f64::consts::TAU), rng.range(1.2, 2.2)))
            .collect();
        Metal {
            bloat: rng.range(0.5, 0.9),
            streaks,
            z0: t.shape.z_widest - 1.5,
            z_mid: 0.5 * (t.shape.z_widest + t.shape.crown_height),
        }
    }

    /// Extra inflation (mm) at local point `l`.
    fn inflation(&self, l: DVec3) -> f64 {
        let w = ((l.z - self.z0) / 1.0).clamp(0.0, 1.0);
        if w <= 0.0 {
            return 0.0;
        }
        let ang = l.y.atan2(l.x);
        let mut spike: f64 = 0.0;
        for &(a, amp) in &self.streaks {
            let mut d = (ang - a).rem_euclid(std::f64::consts::TAU);
            if d > std::f64::consts::PI {
                d -= std::f64::consts::TAU;
            }
            let dz = (l.z - self.z_mid) / 1.2;
            spike = spike.max(amp * (-(d / 0.1).powi(2) - dz * dz).exp());
        }
        w * (self.bloat + spike)
    }
}

/// One neighbour's influence on a tooth's CBCT segmentation.
pub struct Neighbour<'a> {
    /// The neighbour tooth (world).
    pub tooth: &'a PlacedTooth,
    /// Its segmentation bias (mm).
    pub bias: f64,
    /// Contact point (world).
    pub contact: DVec3,
    /// Unit normal of the split plane, pointing towards the neighbour (world).
    pub normal: DVec3,
}

fn blur_axis(v: &mut [f32], dims: [usize; 3], axis: usize, kernel: &[f32]) {
    let r = kernel.len() / 2;
    let n = dims[axis];
    let stride = match axis {
        0 => 1,
        1 => dims[0],
        _ => dims[0] * dims[1],
    };
    let mut line = vec![0f32; n];
    let (o1, o2) = match axis {
        0 => (dims[1], dims[2]),
        1 => (dims[0], dims[2]),
        _ => (dims[0], dims[1]),
    };
    for b in 0..o2 {
        for a in 0..o1 {
            let base = match axis {
                0 => dims[0] * (a + dims[1] * b),
                1 => a + dims[0] * dims[1] * b,
                _ => a + dims[0] * b,
            };
            for (i, l) in line.iter_mut().enumerate() {
                *l = v[base + i * stride];
            }
            for i in 0..n {
                let mut s = 0f32;
                for (k, &w) in kernel.iter().enumerate() {
                    let j = i as isize + k as isize - r as isize;
                    if j >= 0 && (j as usize) < n {
                        s += w * line[j as usize];
                    }
                }
                v[base + i * stride] = s;
            }
        }
    }
}

/// Simulates the CBCT mesh of tooth `t` in the CBCT frame.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    t: &PlacedTooth,
    bias: f64,
    metal: Option<&Metal>,
    neighbours: &[Neighbour<'_>],
    world_to_cbct: &Rigid,
    distortion: &Distortion,
    realism: &CbctRealism,
    rng: &mut Rng,
) -> TriMesh {
    let cbct_to_world = world_to_cbct.inverse();
    let (llo, lhi) = t.shape.local_box();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for c in 0..8 {
        let l = DVec3::new(
            if c & 1 == 0 { llo.x } else { lhi.x },
            if c & 2 == 0 { llo.y } else { lhi.y },
            if c & 4 == 0 { llo.z } else { lhi.z },
        );
        let q = world_to_cbct.apply(t.to_world(l));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let pad = if metal.is_some() { 3.0 } else { 1.5 };
    let h = realism.voxel;
    // Snap to the scanner's voxel lattice (multiples of h in the CBCT frame).
    let lo = ((lo - DVec3::splat(pad)) / h).floor() * h;
    let hi = ((hi + DVec3::splat(pad)) / h).ceil() * h;
    // The tooth's own (biased, possibly bloated) field, coarse-to-fine.
    let mut g = Grid::covering(lo, hi, h, 0);
    let lip = if metal.is_some() { 8.0 } else { 2.0 };
    g.fill(16, lip, |x| {
        let l = t.to_local(cbct_to_world.apply(x));
        let infl = bias + metal.map_or(0.0, |m| m.inflation(l));
        t.shape.eval(l) - infl
    });
    let dims = g.dims;
    let occ = |f: f64| (0.5 - f / h).clamp(0.0, 1.0);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let id = g.idx(i, j, k);
                let own = g.values[id] as f64;
                let mut o = occ(own);
                let near = own < 2.0;
                if near {
                    let p = cbct_to_world.apply(g.point(i, j, k));
                    for nb in neighbours {
                        let d = p - nb.contact;
                        let s = d.dot(nb.normal);
                        if s > -1.0 && (d - nb.normal * s).length() < 7.0 {
                            o += occ(nb.tooth.eval(p) - nb.bias);
                        }
                    }
                }
                // Noise matters only where the blurred image can cross the threshold.
                let noise = if near && own > -2.0 {
                    realism.noise * rng.normal()
                } else {
                    0.0
                };
                g.values[id] = (o.min(1.0) + noise) as f32;
            }
        }
    }
    if realism.blur_sigma > 0.0 {
        let s = realism.blur_sigma / h;
        let r = (3.0 * s).ceil() as isize;
        let mut kernel: Vec<f32> = (-r..=r)
            .map(|x| (-(x * x) as f64 / (2.0 * s * s)).exp() as f32)
            .collect();
        let sum: f32 = kernel.iter().sum();
        kernel.iter_mut().for_each(|w| *w /= sum);
        for axis in 0..3 {
            blur_axis(&mut g.values, dims, axis, &kernel);
        }
    }
    // Segmentation: inside where the blurred image exceeds 1/2; split planes at contacts.
    let mut seg = if (realism.mesh_spacing - h).abs() < 1e-9 {
        let mut s = g.clone();
        for v in &mut s.values {
            *v = 0.5 - *v;
        }
        s
    } else {
        let mut s = Grid::covering(lo, hi, realism.mesh_spacing, 0);
        let sd = s.dims;
        for k in 0..sd[2] {
            for j in 0..sd[1] {
                for i in 0..sd[0] {
                    let x = s.point(i, j, k);
                    let id = s.idx(i, j, k);
                    s.values[id] = 0.5 - trilinear(&g, x);
                }
            }
        }
        s
    };
    if realism.contact_flattening && !neighbours.is_empty() {
        let sd = seg.dims;
        for k in 0..sd[2] {
            for j in 0..sd[1] {
                for i in 0..sd[0] {
                    let p = cbct_to_world.apply(seg.point(i, j, k));
                    let id = seg.idx(i, j, k);
                    for nb in neighbours {
                        let d = p - nb.contact;
                        let s = d.dot(nb.normal);
                        if (d - nb.normal * s).length() < 7.0 {
                            seg.values[id] = seg.values[id].max(s as f32);
                        }
                    }
                }
            }
        }
    }
    seg.force_border_outside();
    let mut mesh = extract_closed(&mut seg);
    for p in &mut mesh.positions {
        *p += distortion.at(*p);
    }
    mesh
}

fn trilinear(g: &Grid, x: DVec3) -> f32 {
    let f = (x - g.origin) / g.h;
    let [nx, ny, nz] = g.dims;
    let i = (f.x.floor().max(0.0) as usize).min(nx - 2);
    let j = (f.y.floor().max(0.0) as usize).min(ny - 2);
    let k = (f.z.floor().max(0.0) as usize).min(nz - 2);
    let (tx, ty, tz) = (
        (f.x - i as f64).clamp(0.0, 1.0) as f32,
        (f.y - j as f64).clamp(0.0, 1.0) as f32,
        (f.z - k as f64).clamp(0.0, 1.0) as f32,
    );
    let v = |a, b, c| g.values[g.idx(a, b, c)];
    let l = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = l(v(i, j, k), v(i + 1, j, k), tx);
    let x10 = l(v(i, j + 1, k), v(i + 1, j + 1, k), tx);
    let x01 = l(v(i, j, k + 1), v(i + 1, j, k + 1), tx);
    let x11 = l(v(i, j + 1, k + 1), v(i + 1, j + 1, k + 1), tx);
    l(l(x00, x10, ty), l(x01, x11, ty), tz)
}
