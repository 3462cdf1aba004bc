//! Shared helpers for the io tests: a scratch folder and a deterministic test mesh.
#![allow(dead_code)]

use glam::DVec3;
use std::path::PathBuf;
use toothfuse::TriMesh;

/// A fresh scratch folder for one test (removed first if left over).
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("toothfuse_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Deterministic pseudo-random numbers in [0, 1) (64-bit LCG, high bits).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// An `n`×`n` grid surface with jittered full-precision f64 coordinates (not f32-representable)
/// and 2(n-1)² triangles.
pub fn grid(n: usize, seed: u64) -> TriMesh {
    let mut r = Lcg(seed);
    let mut pos = Vec::new();
    for j in 0..n {
        for i in 0..n {
            pos.push(DVec3::new(
                i as f64 * 0.3 + 0.1 * r.next(),
                j as f64 * 0.3 + 0.1 * r.next(),
                5.0 * r.next() - 20.0,
            ));
        }
    }
    let mut tris = Vec::new();
    let id = |i: usize, j: usize| (j * n + i) as u32;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(pos, tris)
}

/// The same grid with coordinates rounded to f32 (for formats that store f32).
pub fn grid_f32(n: usize, seed: u64) -> TriMesh {
    let mut m = grid(n, seed);
    for p in &mut m.positions {
        *p = DVec3::new(p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64);
    }
    m
}

/// Writes `bytes` to `dir/name` and returns the path.
pub fn put(dir: &std::path::Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}
