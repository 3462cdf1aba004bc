//! Builds reused: the same tooth bit for bit, keys that tell inputs apart, and no build kept
//! that its band's part does not make again.

use super::*;
use crate::arch::Jaw;
use crate::fuse::assembly::cut_side;
use crate::fuse::{CutJaw, FusedTooth, stitch_tooth};
use crate::phantom::{IosExport, Phantom, PhantomOptions, Variant};
use crate::pipeline::{PipelineOptions, transforms_of};

/// The seed-53 upper jaw with stitching drift as a coarse export, registered and cut as the
/// library's one-call fuse does: its incisors' remedies come back to crown sides they built
/// from before (tooth 12: 7 builds made, 20 asked for again, when this test was written). Made
/// once for the tests of this file.
fn cut_jaw_53() -> &'static CutJaw {
    static JAW: std::sync::OnceLock<CutJaw> = std::sync::OnceLock::new();
    JAW.get_or_init(made_jaw_53)
}

fn made_jaw_53() -> CutJaw {
    let mut po = PhantomOptions {
        seed: 53,
        jaw: Jaw::Upper,
        variant: Variant::from_name("drift").expect("variant"),
        ..PhantomOptions::default()
    };
    po.realism.ios.rough = IosExport::Coarse.roughness();
    let p = Phantom::generate(&po).expect("phantom");
    let crowns = crate::fuse::ios_crowns(&p.ios).expect("crowns");
    let opts = PipelineOptions::default();
    let mut ro = opts.register.clone();
    ro.frame = opts.frame;
    let reg = crate::register::register(&crowns, &p.cbct, &ro).expect("registration");
    crate::fuse::jaw::cut_crowns(&crowns, &p.cbct, &transforms_of(&reg), &opts.fuse)
}

/// `ct` stitched with builds reused or, with `reuse` false, every build made.
fn stitched(ct: &CutTooth, reuse: bool) -> FusedTooth {
    OFF.with(|o| o.set(!reuse));
    let f = stitch_tooth(ct, &FuseOptions::default());
    OFF.with(|o| o.set(false));
    f.expect("the tooth stitches")
}

fn bits(f: &FusedTooth) -> Vec<u64> {
    f.mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn a_build_asked_for_again_is_reused_and_the_tooth_is_the_same_bit_for_bit() {
    let cut = cut_jaw_53();
    let mut reused_teeth = 0;
    for fdi in [12, 22] {
        let ct = &cut.teeth[&fdi];
        let on = stitched(ct, true);
        let off = stitched(ct, false);
        assert_eq!(off.band_builds_reused, 0, "tooth {fdi}");
        assert_eq!(
            on.band_builds + on.band_builds_reused,
            off.band_builds,
            "tooth {fdi}: the remedies ask for the same builds"
        );
        assert!(on.band_builds < off.band_builds || on.band_builds_reused == 0);
        reused_teeth += usize::from(on.band_builds_reused > 0);
        assert_eq!(bits(&on), bits(&off), "tooth {fdi}: positions");
        assert_eq!(on.mesh.triangles, off.mesh.triangles, "tooth {fdi}: faces");
        assert_eq!(on.source, off.source, "tooth {fdi}");
        assert_eq!(on.ios_vertex, off.ios_vertex, "tooth {fdi}");
        assert_eq!(on.band_faces, off.band_faces, "tooth {fdi}");
        assert_eq!(on.crown_faces_added, off.crown_faces_added, "tooth {fdi}");
        assert_eq!(on.warnings, off.warnings, "tooth {fdi}");
        let (q, r) = (&on.quality, &off.quality);
        assert_eq!(
            (
                q.band_crossings_left,
                q.ios_vertices_trimmed,
                q.crown_vertices
            ),
            (
                r.band_crossings_left,
                r.ios_vertices_trimmed,
                r.crown_vertices
            ),
            "tooth {fdi}"
        );
        assert_eq!(KEPT.with(|k| k.borrow().len()), 0, "tooth {fdi}: forgotten");
    }
    assert_eq!(reused_teeth, 2, "both incisors go round a cycle of trims");
}

#[test]
fn keys_tell_every_input_apart() {
    let cut = cut_jaw_53();
    let ct = &cut.teeth[&12];
    let side = cut_side(ct);
    let opts = FuseOptions::default();
    let k0 = key(ct, &side, &opts);
    assert_eq!(key(&ct.clone(), &side.clone(), &FuseOptions::default()), k0);
    let mut keys = vec![k0];
    // The sign bit of one crown coordinate, then of two (a word-wise XOR hash cancels those).
    let mut s = side.clone();
    s.crown.positions[3].x = -s.crown.positions[3].x;
    keys.push(key(ct, &s, &opts));
    s.crown.positions[5].y = -s.crown.positions[5].y;
    keys.push(key(ct, &s, &opts));
    let mut s = side.clone();
    s.crown.triangles[0].swap(1, 2);
    keys.push(key(ct, &s, &opts));
    let mut s = side.clone();
    s.margin.rotate_left(1);
    keys.push(key(ct, &s, &opts));
    let mut s = side.clone();
    s.dirs[0] *= -1.0;
    keys.push(key(ct, &s, &opts));
    let mut s = side.clone();
    s.ios_vertex[0] = u32::MAX;
    keys.push(key(ct, &s, &opts));
    let mut s = side.clone();
    s.chords.push(s.chords.first().copied().unwrap_or((
        crate::stitch::BandVertex::Upper(0),
        crate::stitch::BandVertex::Upper(2),
    )));
    keys.push(key(ct, &s, &opts));
    // The root side and the frame.
    let mut t = ct.clone();
    t.root.root.positions[0].z += 1e-12;
    keys.push(key(&t, &side, &opts));
    let mut t = ct.clone();
    t.root.cut_loop.rotate_left(1);
    keys.push(key(&t, &side, &opts));
    let mut t = ct.clone();
    t.root_dirs[0] *= -1.0;
    keys.push(key(&t, &side, &opts));
    let mut t = ct.clone();
    t.frame.axis = -t.frame.axis;
    keys.push(key(&t, &side, &opts));
    // The crown's last vertex taken from its positions and its bits put at the head of its
    // faces (two faces of three 32-bit words): the same bytes in a row, in other lists.
    let mut s = side.clone();
    let p = s.crown.positions.pop().expect("crown vertex");
    let w: Vec<u32> = p
        .to_array()
        .iter()
        .flat_map(|c| {
            let b = c.to_bits();
            [b as u32, (b >> 32) as u32]
        })
        .collect();
    s.crown.triangles.insert(0, [w[3], w[4], w[5]]);
    s.crown.triangles.insert(0, [w[0], w[1], w[2]]);
    keys.push(key(ct, &s, &opts));
    // The stitch options.
    let mut o = opts;
    o.stitch.tangent_scale *= 1.0 + f64::EPSILON;
    keys.push(key(ct, &side, &o));
    let mut o = opts;
    o.stitch.untangle = !o.stitch.untangle;
    keys.push(key(ct, &side, &o));
    let n = keys.len();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), n, "every change makes another key");
}

#[test]
fn a_build_its_band_part_does_not_make_again_is_not_kept() {
    let cut = cut_jaw_53();
    let ct = &cut.teeth[&12];
    let side = cut_side(ct);
    let opts = FuseOptions::default();
    let made = crate::fuse::assembly::assemble(ct, &side, &opts).expect("build");
    clear();
    // Kept as made: found again, from its band's part alone, equal bit for bit.
    keep(key(ct, &side, &opts), ct, &side, &made);
    assert_eq!(KEPT.with(|k| k.borrow().len()), 1);
    ASKED.with(|a| a.set(1));
    let again = build(ct, &side, &opts, || panic!("not made again")).expect("reused");
    assert!(same(&again, &made) && again.untangle == made.untangle);
    // Other inputs: made.
    let mut other = opts;
    other.stitch.tangent_scale *= 0.5;
    let mut asked = false;
    let _ = build(ct, &side, &other, || {
        asked = true;
        crate::fuse::assembly::assemble(ct, &side, &other)
    });
    assert!(asked, "another key is made");
    clear();
    // A crown vertex the build moved, or a root face it changed: not kept.
    let mut moved = made.clone();
    moved.mesh.positions[0].x += 1e-9;
    keep(2, ct, &side, &moved);
    let mut turned = made.clone();
    let last = turned.mesh.triangles.len() - 1;
    turned.mesh.triangles[last].swap(0, 1);
    keep(3, ct, &side, &turned);
    assert_eq!(KEPT.with(|k| k.borrow().len()), 0);
    // Room for MAX_KEPT builds, no more.
    for k in 0..MAX_KEPT as u128 + 3 {
        keep(10 + k, ct, &side, &made);
    }
    assert_eq!(KEPT.with(|k| k.borrow().len()), MAX_KEPT);
    clear();
}
