//! Real anatomy: closed real tooth meshes (e.g. CBCT-segmented Open-Full-Jaw teeth) as the true
//! anatomy. Each tooth gets a local anatomical frame (long axis by PCA, oriented to the wider
//! crown end; mesiodistal axis towards its arch neighbour), its crown measures from its
//! cross-section profile, and a sampled signed distance (ray-parity sign along grid columns,
//! exact point-triangle distance in a narrow band) that stands in for the parametric implicit.

use super::grid::Grid;
use super::layout::PlacedTooth;
use super::rng::Rng;
use super::shape::ToothShape;
use super::voxelize::{column_crossings, inside_samples};
use crate::arch::{Jaw, arch_order};
use crate::mesh::TriMesh;
use crate::{Error, Result, Rigid};
use glam::{DMat3, DVec3};
use std::collections::BTreeMap;

/// A signed distance sampled on a grid (local tooth frame), clamped to a narrow band.
#[derive(Clone, Debug)]
pub struct SampledSdf {
    grid: Grid,
    band: f64,
}

impl SampledSdf {
    /// Samples the signed distance of a closed mesh at spacing `h`, exact within `band` mm of
    /// the surface, ±`band` beyond.
    pub fn new(mesh: &TriMesh, h: f64, band: f64) -> SampledSdf {
        let (lo, hi) =
            crate::geom::bounding_box(&mesh.positions).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let pad = (band / h).ceil() as usize + 2;
        let mut grid = Grid::covering(lo, hi, h, pad);
        let [nx, ny, nz] = grid.dims;
        for v in &mut grid.values {
            *v = band as f32;
        }
        // Unsigned distance, splatted per triangle.
        for t in &mesh.triangles {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let tlo = a.min(b).min(c) - DVec3::splat(band);
            let thi = a.max(b).max(c) + DVec3::splat(band);
            let i0 = ((tlo - grid.origin) / h).ceil().max(DVec3::ZERO);
            let i1 = ((thi - grid.origin) / h).floor();
            for k in i0.z as usize..=(i1.z as usize).min(nz - 1) {
                for j in i0.y as usize..=(i1.y as usize).min(ny - 1) {
                    for i in i0.x as usize..=(i1.x as usize).min(nx - 1) {
                        let d = point_triangle(grid.point(i, j, k), a, b, c) as f32;
                        let id = grid.idx(i, j, k);
                        if d < grid.values[id] {
                            grid.values[id] = d;
                        }
                    }
                }
            }
        }
        // Sign by ray parity along z through each (i, j) column.
        let cols = column_crossings(&mesh.positions, &mesh.triangles, grid.origin, h, grid.dims);
        for j in 0..ny {
            for i in 0..nx {
                inside_samples(&cols[i + nx * j], grid.origin.z, h, nz, |k| {
                    let id = grid.idx(i, j, k);
                    grid.values[id] = -grid.values[id];
                });
            }
        }
        SampledSdf { grid, band }
    }

    /// Box of the sampled region.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let g = &self.grid;
        let ext = DVec3::new(
            g.dims[0] as f64 - 1.0,
            g.dims[1] as f64 - 1.0,
            g.dims[2] as f64 - 1.0,
        ) * g.h;
        (g.origin, g.origin + ext)
    }

    /// Trilinear signed distance; outside the grid, the band plus the distance to the grid.
    pub fn eval(&self, p: DVec3) -> f64 {
        let g = &self.grid;
        let (lo, hi) = self.bounds();
        let out = (lo - p).max(p - hi).max(DVec3::ZERO);
        if out != DVec3::ZERO {
            return self.band + out.length();
        }
        let f = (p - g.origin) / g.h;
        let [nx, ny, nz] = g.dims;
        let i = (f.x.floor() as usize).min(nx - 2);
        let j = (f.y.floor() as usize).min(ny - 2);
        let k = (f.z.floor() as usize).min(nz - 2);
        let (tx, ty, tz) = (f.x - i as f64, f.y - j as f64, f.z - k as f64);
        let v = |a, b, c| g.values[g.idx(a, b, c)] as f64;
        let l = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let x00 = l(v(i, j, k), v(i + 1, j, k), tx);
        let x10 = l(v(i, j + 1, k), v(i + 1, j + 1, k), tx);
        let x01 = l(v(i, j, k + 1), v(i + 1, j, k + 1), tx);
        let x11 = l(v(i, j + 1, k + 1), v(i + 1, j + 1, k + 1), tx);
        l(l(x00, x10, ty), l(x01, x11, ty), tz)
    }
}

/// Distance from `p` to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (p - (a + ab * (d1 / (d1 - d3)))).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (p - (a + ac * (d2 / (d2 - d6)))).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).length();
    }
    let denom = 1.0 / (va + vb + vc);
    (p - (a + ab * (vb * denom) + ac * (vc * denom))).length()
}

/// The real teeth placed for simulation in a canonical jaw frame (occlusal direction ±Z), and
/// the rotation `canon` from the caller's world frame to it.
pub struct RealJaw {
    /// Placed teeth, arch order, canonical frame.
    pub teeth: Vec<PlacedTooth>,
    /// World → canonical (a rotation about the origin).
    pub canon: Rigid,
}

/// Prepares real tooth meshes (closed, mm, world frame) for the simulation.
pub fn prepare(anatomy: &BTreeMap<u8, TriMesh>, jaw: Jaw, rng: &mut Rng) -> Result<RealJaw> {
    let keys: Vec<u8> = anatomy.keys().copied().collect();
    for &k in &keys {
        crate::arch::check_fdi(k as i32)?;
        if crate::arch::jaw_of(k) != jaw {
            return Err(Error::InvalidArgument(format!(
                "tooth {k} is not in the {jaw:?} jaw"
            )));
        }
    }
    let order = arch_order(&keys);
    // Long axes, oriented to the wider (crown) end.
    let mut axes = BTreeMap::new();
    for &fdi in &order {
        let m = &anatomy[&fdi];
        if m.triangles.is_empty() {
            return Err(Error::MissingData("empty tooth mesh".into()).in_tooth(fdi));
        }
        let (c, mut a) = crate::geom::principal_axis(&m.positions)
            .ok_or_else(|| Error::MissingData("empty tooth mesh".into()).in_tooth(fdi))?;
        let ts: Vec<f64> = m.positions.iter().map(|p| (*p - c).dot(a)).collect();
        let (tmin, tmax) = ts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &t| {
                (l.min(t), h.max(t))
            });
        let span = tmax - tmin;
        let radial = |sel: &dyn Fn(f64) -> bool| {
            let v: Vec<f64> = m
                .positions
                .iter()
                .zip(&ts)
                .filter(|(_, t)| sel(**t))
                .map(|(p, t)| (*p - c - a * *t).length())
                .collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let top = radial(&|t| t > tmax - 0.25 * span);
        let bottom = radial(&|t| t < tmin + 0.25 * span);
        if bottom > top {
            a = -a;
        }
        axes.insert(fdi, (c, a));
    }
    let mean_axis = axes
        .values()
        .fold(DVec3::ZERO, |s, (_, a)| s + *a)
        .normalize_or(DVec3::Z);
    let occ = if jaw == Jaw::Upper {
        -DVec3::Z
    } else {
        DVec3::Z
    };
    let rot = DMat3::from_quat(glam::DQuat::from_rotation_arc(mean_axis, occ));
    let canon = Rigid::new(rot, DVec3::ZERO);
    let mut teeth = Vec::new();
    for (idx, &fdi) in order.iter().enumerate() {
        let (c0, a0) = axes[&fdi];
        let c = canon.apply(c0);
        let z = canon.apply_vector(a0).normalize();
        // Mesiodistal direction: towards the next tooth in arch order (or away from the previous).
        let towards = if idx + 1 < order.len() {
            canon.apply(axes[&order[idx + 1]].0) - c
        } else if idx > 0 {
            c - canon.apply(axes[&order[idx - 1]].0)
        } else {
            DVec3::X
        };
        let mut x = towards - z * towards.dot(z);
        if x.length() < 1e-9 {
            x = z.any_orthonormal_vector();
        }
        let x = x.normalize();
        let y = z.cross(x);
        let r = DMat3::from_cols(x, y, z);
        let local: Vec<DVec3> = anatomy[&fdi]
            .positions
            .iter()
            .map(|p| r.transpose() * (canon.apply(*p) - c))
            .collect();
        // Cross-section profile along the axis: the widest mesiodistal extent in the upper half.
        let (zmin, zmax) = local
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p.z), h.max(p.z))
            });
        let bins = (((zmax - zmin) / 0.5).ceil() as usize).max(1);
        let mut md = vec![0.0f64; bins];
        let mut bl = vec![0.0f64; bins];
        for p in &local {
            let b = (((p.z - zmin) / 0.5) as usize).min(bins - 1);
            md[b] = md[b].max(p.x.abs());
            bl[b] = bl[b].max(p.y.abs());
        }
        let mid = bins / 2;
        let wb = (mid..bins)
            .max_by(|&i, &j| md[i].total_cmp(&md[j]))
            .unwrap_or(mid);
        let z_widest_abs = zmin + (wb as f64 + 0.5) * 0.5;
        // The CEJ sits below the height of contour as in the parametric teeth.
        let z0 = ((z_widest_abs - 0.36 * zmax) / 0.64).min(z_widest_abs - 1.5);
        let center = c + r * DVec3::new(0.0, 0.0, z0);
        let shifted: Vec<DVec3> = local
            .iter()
            .map(|p| *p - DVec3::new(0.0, 0.0, z0))
            .collect();
        let sdf = SampledSdf::new(
            &TriMesh::new(shifted, anatomy[&fdi].triangles.clone()),
            0.25,
            0.75,
        );
        let shape = ToothShape::from_sampled(
            fdi,
            sdf,
            2.0 * md[wb],
            2.0 * bl[wb],
            zmax - z0,
            z0 - zmin,
            z_widest_abs - z0,
        );
        let mut tr = rng.fork(fdi as u64);
        let zw = shape.z_widest;
        let margin = (
            zw - tr.range(1.3, 1.9),
            tr.range(1.0, 1.4),
            (tr.range(0.05, 0.15), tr.range(0.0, std::f64::consts::TAU)),
        );
        teeth.push(PlacedTooth::new(shape, r, center, idx as f64, margin));
    }
    Ok(RealJaw { teeth, canon })
}
