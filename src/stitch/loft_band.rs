//! The loft band (the band before the chart, and the chart band's fallback): interior points on
//! rings graded between the loops, or the paper's recursive interpolation, on a Hermite loft
//! between the smoothed loops, triangulated in a cylindrical plane.

use super::cdt::triangulate;
use super::interp::{self, InterpOptions, ParamPoint};
use super::param::{Loft, LoopParam};
use super::polyline::{mean_edge, smooth, smooth_dirs};
use super::{Band, BandLoops, PointGeneration, StitchOptions};
use crate::cut::ToothFrame;
use crate::{Error, Result};
use glam::DVec3;

/// The loft band: points on rings (or the paper's recursive interpolation) on a Hermite loft
/// between the smoothed loops, triangulated in a cylindrical plane. `order` = the loops' caller
/// indices counter-clockwise, `pts`/`dirs` the loops in that order.
pub(super) fn loft_band(
    loops: &BandLoops,
    frame: &ToothFrame,
    opts: &StitchOptions,
    order: [&[u32]; 2],
    pts: [&[DVec3]; 2],
    dirs: [&[DVec3]; 2],
) -> Result<Band> {
    let (nu, nl) = (loops.upper.len(), loops.lower.len());
    let [uo, lo] = order;
    let [up_pts, lo_pts] = pts;
    let [up_dirs, lo_dirs] = dirs;
    // The loft (where our interior points live) runs between smoothed copies of the loops, so the
    // loops' vertex-level jaggedness does not leak into the interior.
    let upper = LoopParam::upper(smooth(up_pts, 8), smooth_dirs(up_dirs, 8))?;
    let lower =
        LoopParam::lower_aligned(smooth(lo_pts, 4), smooth_dirs(lo_dirs, 4), &upper, frame)?;
    let loft = Loft::new(upper, lower, opts.tangent_scale);
    let (interior, spacing): (Vec<ParamPoint>, Box<dyn Fn(f64) -> f64>) = match opts.points {
        PointGeneration::Rings | PointGeneration::Chart => {
            let (e_u, e_l) = (mean_edge(up_pts), mean_edge(lo_pts));
            (
                rings(&loft, e_u, e_l),
                Box::new(move |v: f64| e_l + (e_u - e_l) * v),
            )
        }
        PointGeneration::Recursive(io) => {
            let vox = io.voxel;
            (
                recursive(&loft, up_pts, lo_pts, &io),
                Box::new(move |_| vox),
            )
        }
    };
    // Every band vertex is placed in the plane by its own 3D position: angle about the axis,
    // and log of the height scaled by the mean radius (conformal for a cylinder), so planar
    // triangles that do not overlap are 3D triangles that do not overlap on a radial-graph band.
    let r_mean = 0.5 * (loft.upper.length + loft.lower.length) / std::f64::consts::TAU;
    let h0 = lo_pts
        .iter()
        .map(|&p| frame.height(p))
        .fold(f64::INFINITY, f64::min);
    let plane = |p: DVec3| -> [f64; 2] {
        let r = ((frame.height(p) - h0) / r_mean).exp();
        let a = frame.angle(p);
        [r * a.cos(), r * a.sin()]
    };
    let place = |p: &ParamPoint| -> ([f64; 2], f64) {
        let xy = plane(p.pos);
        let rho = (xy[0] * xy[0] + xy[1] * xy[1]).sqrt();
        (xy, 0.4 * spacing(p.v) * rho / r_mean)
    };
    let up_xy: Vec<[f64; 2]> = up_pts.iter().map(|&p| plane(p)).collect();
    let lo_xy: Vec<[f64; 2]> = lo_pts.iter().map(|&p| plane(p)).collect();
    let inner: Vec<([f64; 2], DVec3, f64)> = interior
        .iter()
        .map(|p| {
            let (xy, d) = place(p);
            (xy, p.pos, d)
        })
        .collect();
    match triangulate(&up_xy, &lo_xy, uo, lo, &inner, loops, 0.0) {
        Ok((b, _)) => Ok(b),
        Err(first) => {
            // Fallback when a loop folds back around the axis (the cylindrical projection is not
            // simple): loops on concentric circles by their turn parameter, interior points by
            // theirs. Always a valid annulus; the quality report checks the 3D result.
            let up_raw = LoopParam::upper(up_pts.to_vec(), vec![DVec3::Z; nu])?;
            let lo_raw =
                LoopParam::lower_aligned(lo_pts.to_vec(), vec![DVec3::Z; nl], &up_raw, frame)?;
            let up_xy: Vec<[f64; 2]> = up_raw.phi.iter().map(|&f| loft.plane(f, 1.0)).collect();
            let lo_xy: Vec<[f64; 2]> = lo_raw.phi.iter().map(|&f| loft.plane(f, 0.0)).collect();
            let inner: Vec<([f64; 2], DVec3, f64)> = interior
                .iter()
                .map(|p| {
                    let xy = loft.plane(p.phi, p.v);
                    let rho = (xy[0] * xy[0] + xy[1] * xy[1]).sqrt();
                    (xy, p.pos, 0.4 * spacing(p.v) * rho / r_mean)
                })
                .collect();
            triangulate(&up_xy, &lo_xy, uo, lo, &inner, loops, 0.0)
                .map(|(b, _)| b)
                .map_err(|e| Error::InvalidArgument(format!("{first}; annulus fallback: {e}")))
        }
    }
}

/// Ours: rings between the loops, spacing graded geometrically from the margin's mean edge
/// length (v = 1) to the cut's (v = 0), alternate rings shifted by half a step.
fn rings(loft: &Loft, e_u: f64, e_l: f64) -> Vec<ParamPoint> {
    let h = loft.mean_height;
    let row = 0.866; // equilateral row spacing
    let n = if (e_u - e_l).abs() < 1e-9 {
        (h / (row * e_u)).round()
    } else {
        (h / (row * (e_u - e_l)) * (e_u / e_l).ln()).round()
    }
    .max(1.0) as usize;
    let mut out = Vec::new();
    for k in 1..n {
        let (e, v) = if (e_u - e_l).abs() < 1e-9 {
            (e_u, 1.0 - k as f64 / n as f64)
        } else {
            let e = e_u * (e_l / e_u).powf(k as f64 / n as f64);
            (e, (e - e_l) / (e_u - e_l))
        };
        let len = loft.lower.length + (loft.upper.length - loft.lower.length) * v;
        let count = ((len / e).round() as usize).max(3);
        let shift = if k % 2 == 1 { 0.5 } else { 0.0 };
        for j in 0..count {
            let phi = loft.upper.phi[0] + (j as f64 + shift) / count as f64;
            out.push(ParamPoint {
                pos: loft.point(phi, v),
                phi,
                v,
            });
        }
    }
    out
}

/// Paper: Algorithm 1 between the two loops, then voxel downsampling; points near a loop vertex
/// (closer than half a voxel) are dropped so no sliver forms against the boundary.
fn recursive(loft: &Loft, up: &[DVec3], lo: &[DVec3], o: &InterpOptions) -> Vec<ParamPoint> {
    let a: Vec<ParamPoint> = (0..up.len())
        .map(|i| ParamPoint {
            pos: up[i],
            phi: loft.upper.phi[i],
            v: 1.0,
        })
        .collect();
    let b: Vec<ParamPoint> = (0..lo.len())
        .map(|i| ParamPoint {
            pos: lo[i],
            phi: loft.lower.phi[i],
            v: 0.0,
        })
        .collect();
    let pts = interp::gen_inter_points(&a, &b, o.neighbours, o.per_segment, o.depth);
    let pts = interp::voxel_downsample(&pts, o.voxel);
    let loop_pts: Vec<[f64; 3]> = a.iter().chain(b.iter()).map(|p| p.pos.to_array()).collect();
    let tree =
        kiddo::ImmutableKdTree::<f64, 3>::new_from_slice(&loop_pts).expect("kd-tree over loops");
    let min_d2 = (0.5 * o.voxel).powi(2);
    pts.into_iter()
        .filter(|p| {
            let r = tree
                .query(&p.pos.to_array())
                .nearest_one::<kiddo::SquaredEuclidean<f64>>()
                .execute();
            r.distance >= min_d2
        })
        .collect()
}
