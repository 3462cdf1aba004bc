//! A parametric closed tooth for fusion tests that do not need the full phantom: a deformed
//! sphere (crown up, root down), sampled finely for the IOS crown above a wavy margin and coarsely
//! (and inflated, smoothly distorted) for the CBCT tooth, with known rigid transforms.
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use toothfuse::{Rigid, TriMesh};

/// Point of the true tooth surface at longitude `u` and colatitude `w` (0 = occlusal pole).
pub fn surface_point(u: f64, w: f64, lobes: f64) -> DVec3 {
    let c = w.cos();
    let s = w.sin().max(0.0);
    let z = if c >= 0.0 {
        7.0 * c + 0.35 * s * s * (lobes * u).cos() * c
    } else {
        14.0 * c
    };
    let r = 3.4 * s.powf(0.7) * (1.0 + 0.1 * (2.0 * u).cos() + 0.04 * (3.0 * u).sin() * s);
    DVec3::new(r * u.cos(), r * u.sin(), z)
}

/// Closed UV mesh of the surface: `nu` longitudes, `nw` colatitude steps, outward.
pub fn uv_tooth(nu: usize, nw: usize, lobes: f64, f: impl Fn(f64, f64, DVec3) -> DVec3) -> TriMesh {
    let mut pos = vec![f(0.0, 0.0, surface_point(0.0, 0.0, lobes))];
    for j in 1..nw {
        let w = std::f64::consts::PI * j as f64 / nw as f64;
        for i in 0..nu {
            let u = std::f64::consts::TAU * i as f64 / nu as f64;
            pos.push(f(u, w, surface_point(u, w, lobes)));
        }
    }
    let pi = std::f64::consts::PI;
    pos.push(f(0.0, pi, surface_point(0.0, pi, lobes)));
    let bottom = (pos.len() - 1) as u32;
    let idx = |j: usize, i: usize| (1 + (j - 1) * nu + (i % nu)) as u32;
    let mut tri = Vec::new();
    for i in 0..nu {
        tri.push([0, idx(1, i), idx(1, i + 1)]);
    }
    for j in 1..nw - 1 {
        for i in 0..nu {
            let (a, b, c, d) = (idx(j, i), idx(j, i + 1), idx(j + 1, i), idx(j + 1, i + 1));
            tri.push([a, c, d]);
            tri.push([a, d, b]);
        }
    }
    for i in 0..nu {
        tri.push([idx(nw - 1, i), bottom, idx(nw - 1, i + 1)]);
    }
    let mut m = TriMesh::new(pos, tri);
    if m.signed_volume() < 0.0 {
        m.flip();
    }
    m
}

/// True margin height at longitude `u` (scalloped: higher interproximally).
pub fn margin_z(u: f64) -> f64 {
    0.3 + 0.9 * (2.0 * u).cos()
}

/// A synthetic tooth case.
pub struct Case {
    /// IOS crown, IOS frame.
    pub crown: TriMesh,
    /// CBCT tooth, CBCT frame.
    pub cbct: TriMesh,
    /// True surface, output frame.
    pub truth: TriMesh,
    /// IOS → output.
    pub ios_to_output: Rigid,
    /// CBCT → output.
    pub cbct_to_output: Rigid,
}

/// Builds a case. `bias` inflates the CBCT tooth (mm); `seed` varies the pose and shape.
pub fn case(seed: u64, bias: f64) -> Case {
    let lobes = 3.0 + (seed % 3) as f64;
    let truth = uv_tooth(240, 320, lobes, |_, _, p| p);
    // IOS crown: fine faces whose vertices all lie above the margin.
    let fine = truth.clone();
    let above: Vec<bool> = fine
        .positions
        .iter()
        .map(|p| p.z > margin_z(p.y.atan2(p.x)))
        .collect();
    let mut crown = TriMesh::new(
        fine.positions.clone(),
        fine.triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&v| above[v as usize]))
            .collect(),
    );
    crown.compact();
    // CBCT: coarse, inflated by `bias` plus a smooth distortion.
    let cbct_world = uv_tooth(80, 100, lobes, |u, w, p| {
        let n = DVec3::new(p.x, p.y, 0.4 * p.z).normalize_or_zero();
        p + n * (bias + 0.04 * (u + w * 3.0).sin())
    });
    let s = seed as f64;
    let ios_to_output = Rigid::new(
        DMat3::from_axis_angle(DVec3::new(0.3, 1.0, 0.2).normalize(), 0.4 + 0.1 * s),
        DVec3::new(10.0 + s, -5.0, 3.0),
    );
    let cbct_to_output = Rigid::new(
        DMat3::from_axis_angle(DVec3::new(-0.5, 0.2, 1.0).normalize(), 1.1 - 0.05 * s),
        DVec3::new(-20.0, 4.0 + s, 7.0),
    );
    Case {
        crown: crown.transformed(&ios_to_output.inverse()),
        cbct: cbct_world.transformed(&cbct_to_output.inverse()),
        truth,
        ios_to_output,
        cbct_to_output,
    }
}
