//! A tiny synthetic upper jaw (four teeth, a few hundred vertices) handed to the C ABI as a host
//! would, and the byte-driven mutations the `ffi_fuse` target applies to it before ingest.

use std::f64::consts::{PI, TAU};

/// FDI numbers of the jaw's teeth, in arch order.
pub const TEETH: [i32; 4] = [12, 11, 21, 22];

/// One tooth's closed surface point at longitude `u` and colatitude `w` (crown up, root down).
fn surface_point(u: f64, w: f64) -> [f64; 3] {
    let (c, s) = (w.cos(), w.sin().max(0.0));
    let z = if c >= 0.0 {
        7.0 * c + 0.35 * s * s * (4.0 * u).cos() * c
    } else {
        14.0 * c
    };
    let r = 3.4 * s.powf(0.7) * (1.0 + 0.1 * (2.0 * u).cos());
    [r * u.cos(), r * u.sin(), z]
}

/// A closed UV tooth of `nu` longitudes and `nw` colatitude steps (outward triangles), keeping
/// only the triangles whose vertices all pass `keep` (then unused vertices are dropped).
fn uv_tooth(
    nu: usize,
    nw: usize,
    keep: impl Fn([f64; 3]) -> bool,
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut pos = vec![surface_point(0.0, 0.0)];
    for j in 1..nw {
        for i in 0..nu {
            pos.push(surface_point(
                TAU * i as f64 / nu as f64,
                PI * j as f64 / nw as f64,
            ));
        }
    }
    pos.push(surface_point(0.0, PI));
    let bottom = (pos.len() - 1) as u32;
    let idx = |j: usize, i: usize| (1 + (j - 1) * nu + (i % nu)) as u32;
    let mut tri = Vec::new();
    for i in 0..nu {
        tri.push([0, idx(1, i + 1), idx(1, i)]);
        tri.push([idx(nw - 1, i), idx(nw - 1, i + 1), bottom]);
    }
    for j in 1..nw - 1 {
        for i in 0..nu {
            let (a, b, c, d) = (idx(j, i), idx(j, i + 1), idx(j + 1, i), idx(j + 1, i + 1));
            tri.push([a, d, c]);
            tri.push([a, b, d]);
        }
    }
    tri.retain(|t| t.iter().all(|&v| keep(pos[v as usize])));
    let mut map = vec![u32::MAX; pos.len()];
    let mut out = Vec::new();
    for t in &mut tri {
        for v in t.iter_mut() {
            if map[*v as usize] == u32::MAX {
                map[*v as usize] = out.len() as u32;
                out.push(pos[*v as usize]);
            }
            *v = map[*v as usize];
        }
    }
    (out, tri)
}

/// Places a tooth at arch position `k` (0..4) of the frame (`ios` adds a small rigid offset).
fn place(p: [f64; 3], k: usize, ios: bool) -> [f64; 3] {
    let a = (k as f64 - 1.5) * 0.35;
    let (x, y) = (25.0 * a.sin(), -12.0 * a.cos());
    let q = [p[0] + x, p[1] + y, p[2]];
    if !ios {
        return q;
    }
    let (c, s) = (0.05f64.cos(), 0.05f64.sin());
    [
        c * q[0] - s * q[1] + 1.0,
        s * q[0] + c * q[1] + 2.0,
        q[2] - 0.5,
    ]
}

/// The jaw as a host holds it: the IOS as one labeled mesh (per-vertex FDI labels) and the CBCT
/// as one closed mesh per tooth.
#[derive(Clone, Debug)]
pub struct Jaw {
    /// IOS vertices, x y z packed.
    pub ios_vertices: Vec<f64>,
    /// IOS triangles, 3 indices each.
    pub ios_indices: Vec<u32>,
    /// IOS per-vertex labels.
    pub ios_labels: Vec<i32>,
    /// CBCT teeth: FDI, vertices (packed), indices.
    pub cbct: Vec<(i32, Vec<f64>, Vec<u32>)>,
}

impl Jaw {
    /// The unmutated jaw.
    pub fn new() -> Jaw {
        let mut jaw = Jaw {
            ios_vertices: Vec::new(),
            ios_indices: Vec::new(),
            ios_labels: Vec::new(),
            cbct: Vec::new(),
        };
        for (k, &fdi) in TEETH.iter().enumerate() {
            let (p, t) = uv_tooth(12, 10, |p| {
                p[2] > 0.3 + 0.9 * (2.0 * p[1].atan2(p[0])).cos()
            });
            let base = (jaw.ios_vertices.len() / 3) as u32;
            jaw.ios_vertices
                .extend(p.iter().flat_map(|&q| place(q, k, true)));
            jaw.ios_labels.extend(std::iter::repeat_n(fdi, p.len()));
            jaw.ios_indices
                .extend(t.iter().flatten().map(|&v| v + base));
            let (p, t) = uv_tooth(8, 8, |_| true);
            let v = p.iter().flat_map(|&q| place(q, k, false)).collect();
            jaw.cbct.push((fdi, v, t.into_iter().flatten().collect()));
        }
        jaw
    }
}

impl Default for Jaw {
    fn default() -> Self {
        Self::new()
    }
}

/// How the host passes the jaw and which options it fuses with (decoded from the input).
#[derive(Clone, Copy, Debug, Default)]
pub struct Call {
    /// Pass vertices as float (else double).
    pub float32: bool,
    /// Extra bytes of stride after each vertex's three scalars.
    pub pad: usize,
    /// Labels per face (majority of each triangle's first vertex) instead of per vertex.
    pub face_labels: bool,
    /// Switch on IOS repair before adding.
    pub repair: bool,
    /// Options preset (passed through unchecked, so bad enums are exercised too).
    pub preset: u32,
    /// Output frame.
    pub frame: u32,
    /// Announce fewer vertices than the buffers hold (indices then point past the end).
    pub vertex_count_cut: usize,
}

/// Applies the mutations encoded in `data` (8-byte records: op, target, value) to the jaw and
/// returns how to call the ABI. Every record is interpreted; nothing is out of range for it.
pub fn mutate(jaw: &mut Jaw, data: &[u8]) -> Call {
    // The paper preset unless a record asks otherwise: its registration is the cheaper one per
    // execution under the fuzzer's instrumentation (~1 s against ~3 s for the default preset).
    let mut call = Call::default();
    for r in data.chunks_exact(8) {
        let target = u16::from_le_bytes([r[1], r[2]]) as usize;
        let raw = [r[3], r[4], r[5], r[6]];
        let f = f32::from_le_bytes(raw) as f64;
        let u = u32::from_le_bytes(raw);
        let small = (r[3] as i8) as f64 * 0.05;
        let t = (r[7] as usize) % TEETH.len();
        match r[0] % 16 {
            0 => nudge(&mut jaw.ios_vertices, target, small),
            1 => nudge(&mut jaw.cbct[t].1, target, small),
            2 => set(&mut jaw.ios_vertices, target, f),
            3 => set(&mut jaw.cbct[t].1, target, f),
            4 => set(&mut jaw.ios_indices, target, u),
            5 => set(&mut jaw.cbct[t].2, target, u),
            6 => set(&mut jaw.ios_labels, target, u as i32),
            7 => remove(&mut jaw.ios_indices, target),
            8 => remove(&mut jaw.cbct[t].2, target),
            9 => jaw.cbct[t].0 = u as i32,
            10 => scale(&mut jaw.ios_vertices, f),
            11 => scale(&mut jaw.cbct[t].1, f),
            12 => mirror(&mut jaw.ios_vertices, &mut jaw.ios_indices),
            13 => relabel_tooth(jaw, t, u as i32),
            14 => {
                call.float32 = r[3] & 1 != 0;
                call.pad = (r[4] % 3) as usize * 4;
                call.face_labels = r[5] & 1 != 0;
                call.repair = r[6] & 1 != 0;
            }
            _ => {
                call.preset = r[3] as u32 % 3;
                call.frame = r[4] as u32 % 3;
                call.vertex_count_cut = r[5] as usize % 4;
            }
        }
    }
    call
}

fn nudge(v: &mut [f64], i: usize, d: f64) {
    if !v.is_empty() {
        let n = v.len();
        v[i % n] += d;
    }
}

fn set<T>(v: &mut [T], i: usize, x: T) {
    if !v.is_empty() {
        let n = v.len();
        v[i % n] = x;
    }
}

/// Removes the triangle holding index `i`.
fn remove(idx: &mut Vec<u32>, i: usize) {
    if idx.len() >= 3 {
        let t = (i % (idx.len() / 3)) * 3;
        idx.drain(t..t + 3);
    }
}

/// Scales a mesh about the origin (units: a factor like 0.001 or 10 mimics metres or cm).
fn scale(v: &mut [f64], f: f64) {
    v.iter_mut().for_each(|x| *x *= f);
}

/// Reflects x and reverses the triangles (a mirrored scan that is still outward-oriented).
fn mirror(v: &mut [f64], idx: &mut [u32]) {
    v.iter_mut().step_by(3).for_each(|x| *x = -*x);
    idx.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
}

/// Gives every IOS vertex labelled like tooth `t` the label `to` (misnumbered or merged teeth).
fn relabel_tooth(jaw: &mut Jaw, t: usize, to: i32) {
    let from = TEETH[t];
    jaw.ios_labels
        .iter_mut()
        .filter(|l| **l == from)
        .for_each(|l| *l = to);
}
