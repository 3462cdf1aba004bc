//! Band builds of one tooth kept for reuse. The remedies derive crown sides from one another by
//! trimming, and on the teeth they cannot clear they come back, build after build, to a crown
//! side, root and options they have built from before: the trims go round a cycle. A build
//! ([`super::assembly::assemble`]) is a pure function of those inputs (the band laid out from
//! the two loops, optimised and untangled; nothing else is read, no cancel is asked mid-build),
//! so a build asked for again is the one already made: it is taken from here instead of being
//! made again, and every output stays the same bit for bit.
//!
//! - **Key**: a 128-bit SipHash of every input a build reads, as bits (the crown side's
//!   positions, faces, margin, directions, chords and IOS indices; the root's positions, faces,
//!   cut loop, directions and chords; the tooth frame; the stitch options). Inputs are told
//!   apart by their keys alone: two different inputs with one key, a chance of ~2^-128 per pair
//!   of a tooth's at most [`MAX_KEPT`] builds, would reuse the wrong build.
//! - **What is kept**: only the band's part of a build (its new vertices' final positions, its
//!   faces, the untangling's report). The crown and root parts are the inputs' own: a build is
//!   kept only after the mesh joined again from that part ([`super::assembly::joined`]) is found
//!   equal to the build bit for bit, so a reused build is the build made, not a likeness of it.
//! - **Cost**: a tooth's first build is neither keyed nor kept (a clean tooth makes one build and
//!   pays nothing here); at most [`MAX_KEPT`] builds are kept per tooth (a few MB on the largest
//!   rough bands), later ones are made as before. The memo lives in a thread-local, emptied where
//!   the tooth's stitching starts and ends ([`super::build_budget::Scope`]): a tooth is stitched
//!   on one thread from start to end, so what the threads do never meets.
//!
//! The builds a remedy asks for still count against the tooth's budget
//! ([`super::build_budget`]) whether made or reused, so the remedies choose what they chose
//! before; [`super::FusedTooth::band_builds`] counts the builds made and
//! [`super::FusedTooth::band_builds_reused`] those reused.

use super::FuseOptions;
use super::assembly::{Assembled, CrownSide, joined};
use super::tooth::CutTooth;
use crate::stitch::BandVertex;
use glam::DVec3;
use std::cell::{Cell, RefCell};
use std::hash::{DefaultHasher, Hasher};

/// Builds kept per tooth at most (past it, later builds are made and not kept).
pub(super) const MAX_KEPT: usize = 64;

/// The band's part of one build: what [`joined`] needs to make the whole build again.
struct Kept {
    key: u128,
    points: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    untangle: Option<super::untangle::UntangleReport>,
}

thread_local! {
    /// The builds kept for the tooth being stitched on this thread.
    static KEPT: RefCell<Vec<Kept>> = const { RefCell::new(Vec::new()) };
    /// Builds asked for by the tooth being stitched on this thread (made or reused).
    static ASKED: Cell<usize> = const { Cell::new(0) };
    /// Builds reused on this thread, over every tooth: what [`all_reused`] reads.
    static REUSED: Cell<usize> = const { Cell::new(0) };
    /// Tests: every build made, none kept nor reused.
    #[cfg(test)]
    static OFF: Cell<bool> = const { Cell::new(false) };
}

/// Forgets every build kept (a tooth's stitching starts or ends).
pub(super) fn clear() {
    KEPT.with(|k| k.borrow_mut().clear());
    ASKED.with(|a| a.set(0));
}

/// Builds reused on this thread so far: the difference over a tooth's stitching is the builds
/// it reused.
pub(super) fn all_reused() -> usize {
    REUSED.with(Cell::get)
}

/// A build from `side` on `ct`'s root with `opts`: the one kept when the same inputs were built
/// before on this tooth, else `make()`'s (kept for later when it can be).
pub(super) fn build(
    ct: &CutTooth,
    side: &CrownSide,
    opts: &FuseOptions,
    make: impl FnOnce() -> crate::Result<Assembled>,
) -> crate::Result<Assembled> {
    let first = ASKED.with(|a| a.replace(a.get() + 1)) == 0;
    #[cfg(test)]
    let first = first || OFF.with(Cell::get);
    if first {
        return make();
    }
    let key = key(ct, side, opts);
    let found = KEPT.with(|k| {
        let k = k.borrow();
        let kept = k.iter().find(|e| e.key == key)?;
        let mut a = joined(ct, side, &kept.points, &kept.triangles);
        a.untangle = kept.untangle.clone();
        Some(a)
    });
    if let Some(a) = found {
        REUSED.with(|r| r.set(r.get() + 1));
        return Ok(a);
    }
    let a = make()?;
    keep(key, ct, side, &a);
    Ok(a)
}

/// Keeps the band's part of `a` under `key` when there is room and [`joined`] makes `a` again
/// from it bit for bit.
fn keep(key: u128, ct: &CutTooth, side: &CrownSide, a: &Assembled) {
    if KEPT.with(|k| k.borrow().len()) >= MAX_KEPT {
        return;
    }
    let band_off = side.crown.positions.len();
    let root_off = a.mesh.positions.len() - ct.root.root.positions.len();
    let Some(points) = a.mesh.positions.get(band_off..root_off) else {
        return;
    };
    let Some(triangles) = a.mesh.triangles.get(a.band.clone()) else {
        return;
    };
    let again = joined(ct, side, points, triangles);
    if !same(&again, a) {
        return;
    }
    KEPT.with(|k| {
        k.borrow_mut().push(Kept {
            key,
            points: points.to_vec(),
            triangles: triangles.to_vec(),
            untangle: a.untangle.clone(),
        })
    });
}

/// Whether two builds' meshes, vertex sources, IOS indices and band ranges are equal bit for
/// bit (their untangling reports aside: the kept one is reused as it is).
fn same(x: &Assembled, y: &Assembled) -> bool {
    let bits = |p: &DVec3| p.to_array().map(f64::to_bits);
    x.mesh.positions.len() == y.mesh.positions.len()
        && x.mesh
            .positions
            .iter()
            .zip(&y.mesh.positions)
            .all(|(p, q)| bits(p) == bits(q))
        && x.mesh.triangles == y.mesh.triangles
        && x.source == y.source
        && x.ios_vertex == y.ios_vertex
        && x.band == y.band
        && x.crown_vertices == y.crown_vertices
}

/// Two SipHash states fed the same bytes after different first bytes: 128 bits. The bytes are
/// gathered and fed in blocks (SipHash is several times faster over a block than word by word).
struct Key {
    a: DefaultHasher,
    b: DefaultHasher,
    buf: Vec<u8>,
}

/// Bytes gathered before they are fed to the hashers.
const BLOCK: usize = 1 << 14;

impl Key {
    fn new() -> Key {
        let (mut a, mut b) = (DefaultHasher::new(), DefaultHasher::new());
        a.write_u8(0);
        b.write_u8(1);
        Key {
            a,
            b,
            buf: Vec::with_capacity(BLOCK + 64),
        }
    }

    fn bytes(&mut self, x: &[u8]) {
        self.buf.extend_from_slice(x);
        if self.buf.len() >= BLOCK {
            self.flush();
        }
    }

    fn flush(&mut self) {
        self.a.write(&self.buf);
        self.b.write(&self.buf);
        self.buf.clear();
    }

    /// A list's length first: lists that end where others begin do not meet (each list's items
    /// have one width).
    fn len(&mut self, n: usize) {
        self.bytes(&(n as u64).to_le_bytes());
    }

    fn points(&mut self, ps: &[DVec3]) {
        self.len(ps.len());
        for p in ps {
            for c in p.to_array() {
                self.bytes(&c.to_bits().to_le_bytes());
            }
        }
    }

    fn indices(&mut self, vs: &[u32]) {
        self.len(vs.len());
        for v in vs {
            self.bytes(&v.to_le_bytes());
        }
    }

    fn faces(&mut self, ts: &[[u32; 3]]) {
        self.len(ts.len());
        for t in ts {
            for v in t {
                self.bytes(&v.to_le_bytes());
            }
        }
    }

    fn chords(&mut self, cs: impl ExactSizeIterator<Item = (BandVertex, BandVertex)>) {
        self.len(cs.len());
        for (x, y) in cs {
            for v in [x, y] {
                let (tag, i) = match v {
                    BandVertex::Upper(i) => (0u8, i),
                    BandVertex::Lower(i) => (1, i),
                    BandVertex::Interior(i) => (2, i),
                };
                self.bytes(&[tag]);
                self.bytes(&i.to_le_bytes());
            }
        }
    }

    fn text(&mut self, s: &str) {
        self.len(s.len());
        self.bytes(s.as_bytes());
    }

    fn finish(mut self) -> u128 {
        self.flush();
        (u128::from(self.a.finish()) << 64) | u128::from(self.b.finish())
    }
}

/// The key of a build from `side` on `ct`'s root with `opts`: every input the build reads.
fn key(ct: &CutTooth, side: &CrownSide, opts: &FuseOptions) -> u128 {
    let mut k = Key::new();
    k.points(&side.crown.positions);
    k.faces(&side.crown.triangles);
    k.indices(&side.margin);
    k.points(&side.dirs);
    k.indices(&side.ios_vertex);
    k.chords(side.chords.iter().copied());
    let rc = &ct.root;
    k.points(&rc.root.positions);
    k.faces(&rc.root.triangles);
    k.indices(&rc.cut_loop);
    k.points(&ct.root_dirs);
    let root_chords: Vec<_> = ct.root_chords().collect();
    k.chords(root_chords.into_iter());
    let f = &ct.frame;
    k.points(&[f.center, f.axis, f.e1, f.e2]);
    // Debug output of floats round-trips exactly: equal text, equal options.
    k.text(&format!("{:?}", opts.stitch));
    k.finish()
}

#[cfg(test)]
mod tests;
