//! The one-call fuse through the C ABI on a small synthetic jaw: fused meshes (view and copy-out
//! agree), every IOS crown vertex kept at its transformed position, quality, whole-jaw labels,
//! report JSON, and error paths (wrong state, missing data, results kept on failure).

mod ffi_common;

use ffi_common::{Session, add_phantom, phantom, report_json};
use glam::DVec3;
use std::collections::BTreeSet;
use std::ptr;
use toothfuse::ffi::*;
use toothfuse::{Rigid, TriMesh};

fn fused_teeth(s: &Session) -> Vec<i32> {
    let mut out = [0i32; 52];
    let mut n = 0usize;
    // SAFETY: live session, room for 52.
    let st = unsafe { toothfuse_session_fused_teeth(s.0, out.as_mut_ptr(), 52, &mut n) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    out[..n].to_vec()
}

/// Positions, indices and sources of fused mesh `fdi` by copy-out, checked against the view.
fn fused(s: &Session, fdi: i32) -> (Vec<DVec3>, Vec<u32>, Vec<u8>) {
    let (mut nv, mut ni) = (0usize, 0usize);
    let mut view = toothfuse_fused_view {
        positions: ptr::null(),
        vertex_count: 0,
        indices: ptr::null(),
        index_count: 0,
        source: ptr::null(),
        labels: ptr::null(),
    };
    // SAFETY: live session; buffers sized from the size query; the view is read before any
    // other call changes the session.
    unsafe {
        assert_eq!(
            toothfuse_session_fused_size(s.0, fdi, &mut nv, &mut ni),
            toothfuse_status::Ok
        );
        let mut v = vec![0f64; 3 * nv];
        let mut t = vec![0u32; ni];
        let mut src = vec![9u8; nv];
        assert_eq!(
            toothfuse_session_copy_fused_vertices(
                s.0,
                fdi,
                v.as_mut_ptr().cast(),
                nv,
                24,
                TOOTHFUSE_SCALAR_FLOAT64
            ),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_copy_fused_indices(s.0, fdi, t.as_mut_ptr(), ni),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_copy_fused_sources(s.0, fdi, src.as_mut_ptr(), nv),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_copy_fused_indices(s.0, fdi, t.as_mut_ptr(), ni - 1),
            toothfuse_status::BufferTooSmall
        );
        assert_eq!(
            toothfuse_session_fused_view(s.0, fdi, &mut view),
            toothfuse_status::Ok
        );
        assert_eq!((view.vertex_count, view.index_count), (nv, ni));
        assert_eq!(std::slice::from_raw_parts(view.positions, 3 * nv), &v[..]);
        assert_eq!(std::slice::from_raw_parts(view.indices, ni), &t[..]);
        assert_eq!(std::slice::from_raw_parts(view.source, nv), &src[..]);
        assert_eq!(view.labels.is_null(), fdi != 0);
        let p = v
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect();
        (p, t, src)
    }
}

#[test]
fn fused_getters_before_fuse_are_wrong_state_and_too_few_teeth_missing_data() {
    let p = phantom(5);
    let s = Session::new();
    let (mut nv, mut ni) = (0usize, 0usize);
    // SAFETY: live session, valid out pointers.
    let st = unsafe { toothfuse_session_fused_size(s.0, 0, &mut nv, &mut ni) };
    assert_eq!(st, toothfuse_status::WrongState);
    assert!(s.error().contains("no fused result"), "{}", s.error());
    add_phantom(&s, &p);
    // Registration alone does not give fused meshes.
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_register(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok);
    let mut q = toothfuse_fused_quality::default();
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_fused_quality(s.0, 11, &mut q) };
    assert_eq!(st, toothfuse_status::WrongState);
    // Fewer than three teeth in both: MISSING_DATA naming them.
    let t = Session::new();
    let (v, tri) = ffi_common::cube(5.0, [0.0; 3]);
    t.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &tri);
    t.add(TOOTHFUSE_MODALITY_IOS, 11, &v, &tri);
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_fuse(t.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::MissingData);
    assert!(
        t.error().contains("at least 3 teeth") && t.error().contains("[11]"),
        "{}",
        t.error()
    );
}

#[test]
fn fuses_a_phantom_closed_manifold_with_every_crown_vertex() {
    let p = phantom(2);
    let s = Session::new();
    add_phantom(&s, &p);
    // SAFETY: live session, NULL options = defaults (frame CBCT).
    let st = unsafe { toothfuse_session_fuse(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let fdis = fused_teeth(&s);
    let both = p
        .truth
        .teeth
        .values()
        .filter(|t| t.in_ios && t.in_cbct)
        .count();
    assert_eq!(fdis.len(), both, "every tooth in both modalities is fused");
    let mut total_vertices = 0;
    for &fdi in &fdis {
        let (pos, tri, src) = fused(&s, fdi);
        total_vertices += pos.len();
        let mut q = toothfuse_fused_quality::default();
        // SAFETY: live session, valid out pointer.
        let st = unsafe { toothfuse_session_fused_quality(s.0, fdi, &mut q) };
        assert_eq!(st, toothfuse_status::Ok);
        assert!(q.closed && q.manifold && q.watertight, "tooth {fdi}: {q:?}");
        assert_eq!(
            (q.boundary_edges, q.non_manifold_edges, q.components),
            (0, 0, 1)
        );
        assert!(q.volume > 0.0 && q.band_faces > 0, "{q:?}");
        // Every triangle's edges are each used by exactly two triangles, opposite ways.
        let mut edges = BTreeSet::new();
        for t in tri.chunks_exact(3) {
            for k in 0..3 {
                assert!(
                    edges.insert((t[k], t[(k + 1) % 3])),
                    "tooth {fdi}: repeated edge"
                );
            }
        }
        assert!(
            edges.iter().all(|&(a, b)| edges.contains(&(b, a))),
            "tooth {fdi}: open edge"
        );
        // Every IOS crown vertex, mapped by IOS→output, is a source-IOS vertex, bit for bit.
        let mut m = [0f64; 16];
        // SAFETY: live session, room for 16.
        let st = unsafe {
            toothfuse_session_transform(s.0, fdi, TOOTHFUSE_TRANSFORM_IOS_TO_OUTPUT, m.as_mut_ptr())
        };
        assert_eq!(st, toothfuse_status::Ok);
        let ios_to_output = Rigid::from_row_major(&m);
        let kept: BTreeSet<[u64; 3]> = pos
            .iter()
            .zip(&src)
            .filter(|(_, s)| **s == TOOTHFUSE_SOURCE_IOS)
            .map(|(q, _)| q.to_array().map(f64::to_bits))
            .collect();
        let crown = s.positions(TOOTHFUSE_MODALITY_IOS, fdi);
        let (mut trimmed, mut reach) = (usize::MAX, f64::NAN);
        // SAFETY: live session, valid out pointers.
        let st = unsafe { toothfuse_session_fused_trim(s.0, fdi, &mut trimmed, &mut reach) };
        assert_eq!(st, toothfuse_status::Ok);
        assert!(
            trimmed * 200 <= crown.len() / 3 && reach <= 0.3,
            "{trimmed} {reach}"
        );
        let mut dropped = usize::MAX;
        // SAFETY: live session, valid out pointer.
        let st = unsafe { toothfuse_session_fused_dropped(s.0, fdi, &mut dropped) };
        assert_eq!(st, toothfuse_status::Ok);
        // The clean phantom's crowns have no stray label islands: nothing dropped.
        assert_eq!(dropped, 0, "tooth {fdi}");
        assert_eq!(kept.len() + trimmed, crown.len() / 3, "tooth {fdi}");
        // The crossings by origin add up to all the fused mesh's crossing pairs (the CBCT root
        // itself does not cross).
        let (mut band, mut own) = (usize::MAX, usize::MAX);
        // SAFETY: live session, valid out pointers.
        let st = unsafe { toothfuse_session_fused_crossings(s.0, fdi, &mut band, &mut own) };
        assert_eq!(st, toothfuse_status::Ok);
        let fused = TriMesh::new(
            pos.clone(),
            tri.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        );
        assert_eq!(
            band + own,
            toothfuse::mesh_check::self_intersections(&fused).len(),
            "tooth {fdi}: band {band}, crown {own}"
        );
        let missing = crown
            .chunks_exact(3)
            .map(|c| ios_to_output.apply(DVec3::new(c[0], c[1], c[2])))
            .filter(|q| !kept.contains(&q.to_array().map(f64::to_bits)))
            .count();
        assert_eq!(
            missing, trimmed,
            "tooth {fdi}: only trimmed vertices are missing"
        );
        assert_eq!(q.crown_vertices, crown.len() / 3 - trimmed);
    }
    // The whole jaw: every fused tooth, labeled by FDI.
    let (pos, _, src) = fused(&s, 0);
    assert_eq!(pos.len(), total_vertices);
    let mut labels = vec![0i32; pos.len()];
    // SAFETY: live session, room for the vertex count.
    let st = unsafe { toothfuse_session_copy_fused_labels(s.0, labels.as_mut_ptr(), labels.len()) };
    assert_eq!(st, toothfuse_status::Ok);
    let found: BTreeSet<i32> = labels.iter().copied().collect();
    assert_eq!(found, fdis.iter().copied().collect());
    assert!(src.iter().all(|&x| x <= TOOTHFUSE_SOURCE_CBCT));
    // The report JSON is the `toothfuse fuse` contract.
    let v: serde_json::Value = serde_json::from_str(&report_json(&s)).unwrap();
    assert_eq!(v["frame"], "cbct");
    let teeth = v["teeth"].as_array().unwrap();
    assert_eq!(teeth.len(), fdis.len());
    assert!(teeth.iter().all(|t| t["watertight"] == true));
    assert!(v["timing_ms"]["total"].as_f64().unwrap() > 0.0);

    // Not fused tooth: MISSING_DATA; a failed fuse keeps the results.
    let mut q = toothfuse_fused_quality::default();
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_fused_quality(s.0, 48, &mut q) };
    assert_eq!(st, toothfuse_status::MissingData);
    assert!(
        s.error().contains("tooth 48 was not fused"),
        "{}",
        s.error()
    );
    let (mut trimmed, mut reach) = (0usize, 0f64);
    // SAFETY: live session, valid out pointers.
    let st = unsafe { toothfuse_session_fused_trim(s.0, 48, &mut trimmed, &mut reach) };
    assert_eq!(st, toothfuse_status::MissingData);
    // SAFETY: live session; a NULL out pointer is refused.
    let st = unsafe { toothfuse_session_fused_trim(s.0, fdis[0], ptr::null_mut(), &mut reach) };
    assert_eq!(st, toothfuse_status::NullParameter);
    assert!(s.error().contains("vertices_out"), "{}", s.error());
    // SAFETY: live session; a NULL out pointer is refused, a tooth not fused is named.
    let st = unsafe { toothfuse_session_fused_dropped(s.0, fdis[0], ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    assert!(s.error().contains("vertices_out"), "{}", s.error());
    // SAFETY: as above.
    let st = unsafe { toothfuse_session_fused_dropped(s.0, 48, &mut trimmed) };
    assert_eq!(st, toothfuse_status::MissingData);
    let mut band = 0usize;
    // SAFETY: live session; a NULL out pointer is refused, a tooth not fused is named.
    let st = unsafe { toothfuse_session_fused_crossings(s.0, fdis[0], &mut band, ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    assert!(s.error().contains("ios_out"), "{}", s.error());
    // SAFETY: as above.
    let st = unsafe { toothfuse_session_fused_crossings(s.0, 48, &mut band, &mut trimmed) };
    assert_eq!(st, toothfuse_status::MissingData);
    let bad = toothfuse_options {
        frame: 2,
        ..toothfuse_options::default()
    };
    // SAFETY: live session, valid options.
    let st = unsafe { toothfuse_session_fuse(s.0, &bad) };
    assert_eq!(st, toothfuse_status::InvalidArgument);
    assert_eq!(fused_teeth(&s), fdis);
    let (pos2, _, _) = fused(&s, 0);
    assert_eq!(pos2, pos);
}

/// Cut and stitch only (`toothfuse_session_fuse_registered`): WRONG_STATE without a
/// registration; after `toothfuse_session_register` it fuses with that registration, and the
/// fused meshes are exactly those of the one-call fuse with the same options.
#[test]
fn fuse_registered_reuses_the_registration_bit_for_bit() {
    let p = phantom(3);
    let s = Session::new();
    add_phantom(&s, &p);
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_fuse_registered(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::WrongState);
    assert!(s.error().contains("no registration"), "{}", s.error());
    // SAFETY: NULL session is refused, not dereferenced.
    let st = unsafe { toothfuse_session_fuse_registered(ptr::null_mut(), ptr::null()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_register(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_fuse_registered(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let teeth = fused_teeth(&s);
    assert!(teeth.len() >= 3, "{teeth:?}");
    let two_step: Vec<_> = teeth.iter().map(|&f| fused(&s, f)).collect();
    let t = Session::new();
    add_phantom(&t, &p);
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_fuse(t.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", t.error());
    assert_eq!(fused_teeth(&t), teeth);
    for (k, &f) in teeth.iter().enumerate() {
        let one_call = fused(&t, f);
        assert_eq!(one_call.0, two_step[k].0, "tooth {f}: positions");
        assert_eq!(one_call.1, two_step[k].1, "tooth {f}: indices");
        assert_eq!(one_call.2, two_step[k].2, "tooth {f}: sources");
    }
}

/// The report JSON of the last fuse, its timings left out.
fn report_without_timing(s: &Session) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(&report_json(s)).unwrap();
    v["timing_ms"] = serde_json::Value::Null;
    v
}

/// A session capped at one thread (everything on the caller's thread) fuses what an uncapped
/// one does, bit for bit; the cap is per session; a NULL session is refused.
#[test]
fn a_session_capped_at_one_thread_fuses_the_same() {
    let p = phantom(3);
    let (capped, free) = (Session::new(), Session::new());
    // SAFETY: live sessions, or NULL.
    unsafe {
        assert_eq!(
            toothfuse_session_set_max_threads(ptr::null_mut(), 1),
            toothfuse_status::NullParameter
        );
        assert_eq!(
            toothfuse_session_set_max_threads(capped.0, 1),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_set_max_threads(free.0, 3),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_set_max_threads(free.0, 0),
            toothfuse_status::Ok
        );
    }
    for s in [&capped, &free] {
        add_phantom(s, &p);
        // SAFETY: live session, NULL options = defaults.
        let st = unsafe { toothfuse_session_fuse(s.0, ptr::null()) };
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    }
    let fdis = fused_teeth(&capped);
    assert!(fdis.len() >= 3, "{fdis:?}");
    assert_eq!(fdis, fused_teeth(&free));
    for fdi in fdis.into_iter().chain([0]) {
        let (a, b) = (fused(&capped, fdi), fused(&free, fdi));
        let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
            v.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
        };
        assert_eq!(bits(&a.0), bits(&b.0), "tooth {fdi}: positions");
        assert_eq!((a.1, a.2), (b.1, b.2), "tooth {fdi}: indices and sources");
    }
    assert_eq!(report_without_timing(&capped), report_without_timing(&free));
}
