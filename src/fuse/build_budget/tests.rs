//! The cap on a tooth's band builds, on a coarse phantom export whose teeth take several.

use super::*;
use crate::fuse::{CutTooth, FuseOptions, FusedTooth, cut_jaw, stitch_tooth};
use crate::phantom::{IosExport, Phantom, PhantomOptions};

/// Lowers the builds allowed per tooth on this thread while it lives.
struct Limit {
    outer: usize,
}

impl Limit {
    fn set(n: usize) -> Limit {
        Limit {
            outer: LIMIT.with(|l| l.replace(n)),
        }
    }
}

impl Drop for Limit {
    fn drop(&mut self) {
        LIMIT.with(|l| l.set(self.outer));
    }
}

/// `ct` stitched, with the builds it made as cut (its own scope) and in all (with the last
/// remedy's new cuts).
fn stitched(ct: &CutTooth) -> (FusedTooth, usize, usize) {
    let all = ALL.with(Cell::get);
    let f = stitch_tooth(ct, &FuseOptions::default()).expect("the tooth stitches");
    let all = ALL.with(Cell::get) - all;
    assert_eq!(f.band_builds, all, "tooth {}: builds reported", ct.fdi);
    (f, LAST.with(Cell::get), all)
}

#[test]
fn a_tooth_makes_at_most_its_allowed_builds_and_stays_closed() {
    let mut po = PhantomOptions {
        seed: 3,
        ..PhantomOptions::default()
    };
    po.realism.ios.rough = IosExport::Coarse.roughness();
    let p = Phantom::generate(&po).expect("phantom");
    let tr = crate::eval::true_transforms(&p);
    let cut = cut_jaw(&p.ios, &p.cbct, &tr, &FuseOptions::default()).expect("cut");
    // Every tooth within the cap; the one with the most builds is the test's.
    let mut most: Option<(&CutTooth, FusedTooth, usize)> = None;
    for ct in cut.teeth.values() {
        let (f, n, all) = stitched(ct);
        assert!(
            (1..=MAX_BUILDS).contains(&n) && all <= 2 * MAX_BUILDS,
            "tooth {}: {n} builds, {all} in all",
            ct.fdi
        );
        if most.as_ref().is_none_or(|m| n > m.2) {
            most = Some((ct, f, n));
        }
    }
    let (ct, full, n) = most.expect("teeth");
    assert!(n >= 4, "tooth {} takes {n} builds", ct.fdi);
    // A cap the tooth does not reach changes nothing.
    {
        let _l = Limit::set(n);
        let (f, m, _) = stitched(ct);
        assert_eq!(m, n);
        assert_eq!(f.mesh, full.mesh);
        assert_eq!(f.source, full.source);
    }
    // Lower caps: no build beyond them, and the tooth is still one closed manifold.
    // (The last two remedies' new cuts, for a tooth the capped builds leave crossed, have a
    // cap of their own each.)
    for cap in [1, 2, n / 2] {
        let _l = Limit::set(cap);
        let (f, m, all) = stitched(ct);
        assert!(m <= cap && m >= 1, "cap {cap}: {m} builds");
        assert!(all <= 3 * cap, "cap {cap}: {all} builds in all");
        let q = &f.quality;
        assert!(
            q.closed && q.manifold && q.components == 1,
            "cap {cap}: {q:?}"
        );
        if cap == 1 {
            assert_eq!(m, 1);
        }
    }
    // A tooth stitched inside another tooth's count (as here, after them) starts from zero and
    // leaves the outer count as it was.
    let outer = Scope::start();
    count();
    count();
    let _ = stitched(ct);
    assert_eq!(made(), 2);
    drop(outer);
    // A progress callback that asks to stop ends the tooth's builds at the next one: it is asked
    // before each build after the first, and once it has asked to stop nothing more is built;
    // the first build is kept, one closed manifold.
    let asked = std::rc::Rc::new(Cell::new(0usize));
    let counter = std::rc::Rc::clone(&asked);
    let (f, m, all) = crate::progress::with_progress(
        move |_| {
            counter.set(counter.get() + 1);
            std::ops::ControlFlow::Break(())
        },
        || stitched(ct),
    );
    assert_eq!((m, all, asked.get()), (1, 1, 1));
    let q = &f.quality;
    assert!(q.closed && q.manifold && q.components == 1, "{q:?}");
}
