//! An opt-in disk cache of generated phantoms, for test suites that make the same jaw in several
//! processes (every test executable, the CLI's `demo` and `eval` runs).
//!
//! Off unless the environment variable [`CACHE_ENV`] names a directory. Each entry is one file
//! named by a 128-bit hash of the options' `Debug` text and of the library's source fingerprint
//! (every file under `src/` and `Cargo.lock`, hashed by `build.rs`), so a changed generator never
//! reads an older jaw. An entry holds every `f64` of the phantom as its bits: a cached jaw is the
//! generated one bit for bit. A missing, short or malformed entry is not an error: the jaw is
//! generated and the entry written again (to a temporary file renamed into place, so that a
//! process reading never sees a half-written entry). Failing to write is ignored.

use super::{Phantom, PhantomOptions, ToothTruth, Truth};
use crate::arch::Jaw;
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Result, Rigid};
use glam::{DMat3, DVec3};
use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;

/// The environment variable naming the cache directory (created when missing).
pub const CACHE_ENV: &str = "TOOTHFUSE_PHANTOM_CACHE";

/// The library's source fingerprint (see the module documentation).
const SOURCE_FINGERPRINT: &str = env!("TOOTHFUSE_SOURCE_FINGERPRINT");

const MAGIC: &[u8; 8] = b"TFPHAN01";

/// `generate(opts)`, read from the cache when [`CACHE_ENV`] is set and holds the entry.
pub(super) fn cached(
    opts: &PhantomOptions,
    generate: impl FnOnce() -> Result<Phantom>,
) -> Result<Phantom> {
    let Some(dir) = std::env::var_os(CACHE_ENV).filter(|d| !d.is_empty()) else {
        return generate();
    };
    let key = key(opts);
    let path = PathBuf::from(dir).join(format!("{:016x}{:016x}.bin", key[0], key[1]));
    if let Some(p) = std::fs::read(&path).ok().and_then(|b| decode(&b, key)) {
        return Ok(p);
    }
    let p = generate()?;
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let written = path
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| std::fs::write(&tmp, encode(&p, key)))
        .and_then(|()| std::fs::rename(&tmp, &path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    Ok(p)
}

/// Two independent 64-bit hashes of the options and the source fingerprint.
fn key(opts: &PhantomOptions) -> [u64; 2] {
    let text = format!("{opts:?}");
    [0u8, 1].map(|salt| {
        let mut h = std::hash::DefaultHasher::new();
        salt.hash(&mut h);
        SOURCE_FINGERPRINT.hash(&mut h);
        text.hash(&mut h);
        h.finish()
    })
}

/// Little-endian writer of the entry.
struct Out(Vec<u8>);

impl Out {
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn vec3(&mut self, v: DVec3) {
        v.to_array().into_iter().for_each(|x| self.f64(x));
    }
    fn rigid(&mut self, r: &Rigid) {
        r.rot.to_cols_array().into_iter().for_each(|x| self.f64(x));
        self.vec3(r.trans);
    }
    fn points(&mut self, p: &[DVec3]) {
        self.u64(p.len() as u64);
        p.iter().for_each(|&v| self.vec3(v));
    }
    fn mesh(&mut self, m: &TriMesh) {
        self.points(&m.positions);
        self.u64(m.triangles.len() as u64);
        for t in &m.triangles {
            t.iter()
                .for_each(|&i| self.0.extend_from_slice(&i.to_le_bytes()));
        }
    }
    fn labels(&mut self, l: &Option<Vec<i32>>) {
        match l {
            None => self.u64(u64::MAX),
            Some(l) => {
                self.u64(l.len() as u64);
                l.iter()
                    .for_each(|&x| self.0.extend_from_slice(&x.to_le_bytes()));
            }
        }
    }
}

fn encode(p: &Phantom, key: [u64; 2]) -> Vec<u8> {
    let mut o = Out(MAGIC.to_vec());
    key.iter().for_each(|&k| o.u64(k));
    o.u64(matches!(p.jaw, Jaw::Lower) as u64);
    o.mesh(&p.ios.mesh);
    o.labels(&p.ios.vertex_labels);
    o.labels(&p.ios.face_labels);
    o.u64(p.cbct.len() as u64);
    for (&fdi, m) in &p.cbct {
        o.u64(fdi as u64);
        o.mesh(m);
    }
    o.u64(p.truth.teeth.len() as u64);
    for t in p.truth.teeth.values() {
        o.u64(t.fdi as u64);
        o.mesh(&t.surface);
        o.points(&t.margin);
        o.vec3(t.axis);
        o.rigid(&t.ios_drift);
        o.rigid(&t.cbct_to_ios);
        let flags = [t.in_ios, t.in_cbct, t.metal_artefact];
        o.u64(
            flags
                .iter()
                .enumerate()
                .map(|(i, &f)| (f as u64) << i)
                .sum(),
        );
    }
    o.rigid(&p.truth.world_to_ios);
    o.rigid(&p.truth.world_to_cbct);
    o.0
}

/// Reader of the entry: `None` at the first short or implausible field.
struct In<'a>(&'a [u8]);

impl In<'_> {
    fn bytes<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.0.split_first_chunk::<N>()?;
        self.0 = rest;
        Some(*head)
    }
    fn u64(&mut self) -> Option<u64> {
        self.bytes().map(u64::from_le_bytes)
    }
    /// A count of items of `size` bytes each that the rest of the entry can hold.
    fn len(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size)? <= self.0.len()).then_some(n)
    }
    fn f64(&mut self) -> Option<f64> {
        self.u64().map(f64::from_bits)
    }
    fn vec3(&mut self) -> Option<DVec3> {
        Some(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    fn rigid(&mut self) -> Option<Rigid> {
        let mut cols = [0.0; 9];
        for c in &mut cols {
            *c = self.f64()?;
        }
        Some(Rigid {
            rot: DMat3::from_cols_array(&cols),
            trans: self.vec3()?,
        })
    }
    fn points(&mut self) -> Option<Vec<DVec3>> {
        let n = self.len(24)?;
        (0..n).map(|_| self.vec3()).collect()
    }
    fn mesh(&mut self) -> Option<TriMesh> {
        let positions = self.points()?;
        let n = self.len(12)?;
        let mut triangles = Vec::with_capacity(n);
        for _ in 0..n {
            let t = [(); 3].map(|()| self.bytes().map(u32::from_le_bytes));
            triangles.push([t[0]?, t[1]?, t[2]?]);
        }
        Some(TriMesh::new(positions, triangles))
    }
    fn labels(&mut self) -> Option<Option<Vec<i32>>> {
        if self.0.get(..8) == Some(&u64::MAX.to_le_bytes()[..]) {
            self.0 = &self.0[8..];
            return Some(None);
        }
        let n = self.len(4)?;
        let l: Option<Vec<i32>> = (0..n)
            .map(|_| self.bytes().map(i32::from_le_bytes))
            .collect();
        l.map(Some)
    }
    fn fdi(&mut self) -> Option<u8> {
        u8::try_from(self.u64()?).ok()
    }
}

fn decode(bytes: &[u8], key: [u64; 2]) -> Option<Phantom> {
    let mut r = In(bytes);
    if &r.bytes::<8>()? != MAGIC || [r.u64()?, r.u64()?] != key {
        return None;
    }
    let jaw = if r.u64()? == 1 {
        Jaw::Lower
    } else {
        Jaw::Upper
    };
    let ios = LabeledMesh {
        mesh: r.mesh()?,
        vertex_labels: r.labels()?,
        face_labels: r.labels()?,
    };
    let mut cbct = BTreeMap::new();
    for _ in 0..r.len(8)? {
        let fdi = r.fdi()?;
        cbct.insert(fdi, r.mesh()?);
    }
    let mut teeth = BTreeMap::new();
    for _ in 0..r.len(8)? {
        let fdi = r.fdi()?;
        let surface = r.mesh()?;
        let margin = r.points()?;
        let (axis, ios_drift, cbct_to_ios) = (r.vec3()?, r.rigid()?, r.rigid()?);
        let flags = r.u64()?;
        let t = ToothTruth {
            fdi,
            surface,
            margin,
            axis,
            ios_drift,
            cbct_to_ios,
            in_ios: flags & 1 != 0,
            in_cbct: flags & 2 != 0,
            metal_artefact: flags & 4 != 0,
        };
        teeth.insert(fdi, t);
    }
    let truth = Truth {
        teeth,
        world_to_ios: r.rigid()?,
        world_to_cbct: r.rigid()?,
    };
    r.0.is_empty().then_some(Phantom {
        jaw,
        ios,
        cbct,
        truth,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::Variant;

    fn small() -> PhantomOptions {
        PhantomOptions {
            seed: 5,
            variant: Variant::PartialArch,
            ..Default::default()
        }
    }

    #[test]
    fn an_entry_reads_back_bit_for_bit_and_a_damaged_one_is_refused() {
        let opts = small();
        let p = Phantom::generate(&opts).expect("phantom");
        let k = key(&opts);
        let bytes = encode(&p, k);
        let back = decode(&bytes, k).expect("entry reads back");
        // Debug prints every f64 exactly (shortest round trip, sign of zero kept).
        assert_eq!(format!("{p:?}"), format!("{back:?}"));
        assert!(decode(&bytes, [k[0], k[1] ^ 1]).is_none(), "another key");
        assert!(
            decode(&bytes[..bytes.len() - 1], k).is_none(),
            "short entry"
        );
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode(&longer, k).is_none(), "trailing bytes");
        let mut huge = bytes.clone();
        // The IOS vertex count (after magic, key and jaw) set beyond the entry.
        huge[32..40].copy_from_slice(&u64::MAX.to_le_bytes()[..]);
        assert!(decode(&huge, k).is_none(), "count beyond the entry");
    }

    #[test]
    fn keys_differ_with_every_option() {
        let a = small();
        let mut b = small();
        b.seed = 6;
        let mut c = small();
        c.realism.ios.noise = 0.011;
        assert_ne!(key(&a), key(&b));
        assert_ne!(key(&a), key(&c));
        assert_eq!(key(&a), key(&small()));
    }
}
