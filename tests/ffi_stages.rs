//! Cut and stitch as separate stages through the C ABI on a small synthetic jaw: register → cut →
//! stitch gives the one-call fuse's and `fuse_registered`'s meshes bit for bit; each cut root is
//! an open manifold disk whose one boundary loop is the reported cut loop and whose vertices are
//! exactly the fused tooth's CBCT part; state rules (no stitch before a cut, no cut before a
//! registration, the cut dropped when the teeth change) and NULL / short-buffer statuses.

mod ffi_common;

use ffi_common::{Session, add_phantom, phantom};
use std::collections::{BTreeMap, BTreeSet};
use std::ptr;
use toothfuse::ffi::*;

type Mesh = (Vec<f64>, Vec<u32>, Vec<u8>);

fn call(s: &Session, st: toothfuse_status) {
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
}

fn teeth(
    s: &Session,
    f: unsafe extern "C" fn(
        *const toothfuse_session,
        *mut i32,
        usize,
        *mut usize,
    ) -> toothfuse_status,
) -> Vec<i32> {
    let mut out = [0i32; 52];
    let mut n = 0usize;
    // SAFETY: live session, room for 52.
    call(s, unsafe { f(s.0, out.as_mut_ptr(), 52, &mut n) });
    out[..n].to_vec()
}

/// Positions (f64 bits as f64), indices and sources of fused tooth `fdi` by copy-out.
fn fused(s: &Session, fdi: i32) -> Mesh {
    let (mut nv, mut ni) = (0usize, 0usize);
    // SAFETY: live session; buffers sized from the size query.
    unsafe {
        call(s, toothfuse_session_fused_size(s.0, fdi, &mut nv, &mut ni));
        let mut v = vec![0f64; 3 * nv];
        let mut t = vec![0u32; ni];
        let mut src = vec![9u8; nv];
        call(
            s,
            toothfuse_session_copy_fused_vertices(
                s.0,
                fdi,
                v.as_mut_ptr().cast(),
                nv,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
            ),
        );
        call(
            s,
            toothfuse_session_copy_fused_indices(s.0, fdi, t.as_mut_ptr(), ni),
        );
        call(
            s,
            toothfuse_session_copy_fused_sources(s.0, fdi, src.as_mut_ptr(), nv),
        );
        (v, t, src)
    }
}

fn all_fused(s: &Session) -> BTreeMap<i32, Mesh> {
    teeth(s, toothfuse_session_fused_teeth)
        .into_iter()
        .map(|f| (f, fused(s, f)))
        .collect()
}

/// The cut root of tooth `fdi`: positions, indices, cut loop (and the f32 copy checked).
fn cut_root(s: &Session, fdi: i32) -> (Vec<f64>, Vec<u32>, Vec<u32>) {
    let (mut nv, mut ni, mut nl) = (0usize, 0usize, 0usize);
    // SAFETY: live session; buffers sized from the size query.
    unsafe {
        call(
            s,
            toothfuse_session_cut_size(s.0, fdi, &mut nv, &mut ni, &mut nl),
        );
        let mut v = vec![0f64; 3 * nv];
        let mut t = vec![0u32; ni];
        let mut lp = vec![0u32; nl];
        call(
            s,
            toothfuse_session_copy_cut_vertices(
                s.0,
                fdi,
                v.as_mut_ptr().cast(),
                nv,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
            ),
        );
        // float, padded stride of 4 floats.
        let mut f = vec![f32::NAN; 4 * nv];
        call(
            s,
            toothfuse_session_copy_cut_vertices(
                s.0,
                fdi,
                f.as_mut_ptr().cast(),
                nv,
                16,
                TOOTHFUSE_SCALAR_FLOAT32,
            ),
        );
        for (a, b) in v.chunks_exact(3).zip(f.chunks_exact(4)) {
            assert_eq!(a.iter().map(|&x| x as f32).collect::<Vec<_>>(), b[..3]);
            assert!(b[3].is_nan(), "padding untouched");
        }
        call(
            s,
            toothfuse_session_copy_cut_indices(s.0, fdi, t.as_mut_ptr(), ni),
        );
        call(
            s,
            toothfuse_session_copy_cut_loop(s.0, fdi, lp.as_mut_ptr(), nl),
        );
        (v, t, lp)
    }
}

/// The one boundary loop of an open mesh, followed along the triangles' own edge direction
/// (surface on the left); panics unless every edge is used once per direction and the boundary
/// is one simple loop.
fn single_boundary_loop(tris: &[u32], fdi: i32) -> Vec<u32> {
    let mut directed = BTreeSet::new();
    for t in tris.chunks_exact(3) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "tooth {fdi}: degenerate"
        );
        for k in 0..3 {
            assert!(
                directed.insert((t[k], t[(k + 1) % 3])),
                "tooth {fdi}: edge used twice in one direction (non-manifold or misoriented)"
            );
        }
    }
    let boundary: Vec<(u32, u32)> = directed
        .iter()
        .copied()
        .filter(|&(a, b)| !directed.contains(&(b, a)))
        .collect();
    assert!(!boundary.is_empty(), "tooth {fdi}: the cut root is closed");
    let mut next = BTreeMap::new();
    for &(a, b) in &boundary {
        assert!(
            next.insert(a, b).is_none(),
            "tooth {fdi}: boundary vertex {a} is singular"
        );
    }
    let start = boundary[0].0;
    let mut lp = vec![start];
    let mut v = next[&start];
    while v != start {
        lp.push(v);
        v = next[&v];
        assert!(
            lp.len() <= boundary.len(),
            "tooth {fdi}: boundary walk loops"
        );
    }
    assert_eq!(
        lp.len(),
        boundary.len(),
        "tooth {fdi}: more than one boundary loop"
    );
    lp
}

fn cyclic_equal(a: &[u32], b: &[u32]) -> bool {
    a.len() == b.len()
        && (a.is_empty()
            || b.iter()
                .position(|&x| x == a[0])
                .is_some_and(|k| (0..a.len()).all(|i| a[i] == b[(k + i) % b.len()])))
}

#[test]
fn stages_give_the_one_call_fuse_bit_for_bit_and_open_one_loop_roots() {
    let p = phantom(3);
    let s = Session::new();
    add_phantom(&s, &p);
    // SAFETY: live sessions, NULL options = defaults, valid out pointers (also below).
    unsafe {
        call(&s, toothfuse_session_register(s.0, ptr::null()));
        call(&s, toothfuse_session_cut(s.0, ptr::null()));
        call(&s, toothfuse_session_stitch(s.0, ptr::null()));
    }
    let staged = all_fused(&s);
    assert!(staged.len() >= 3, "{:?}", staged.keys());
    assert_eq!(teeth(&s, toothfuse_session_cut_teeth), {
        let k: Vec<i32> = staged.keys().copied().collect();
        k
    });
    let one = Session::new();
    add_phantom(&one, &p);
    // SAFETY: as above.
    unsafe { call(&one, toothfuse_session_fuse(one.0, ptr::null())) };
    let reg = Session::new();
    add_phantom(&reg, &p);
    // SAFETY: as above.
    unsafe {
        call(&reg, toothfuse_session_register(reg.0, ptr::null()));
        call(&reg, toothfuse_session_fuse_registered(reg.0, ptr::null()));
    }
    for other in [all_fused(&one), all_fused(&reg)] {
        assert_eq!(
            other.keys().collect::<Vec<_>>(),
            staged.keys().collect::<Vec<_>>()
        );
        for (f, m) in &other {
            let st = &staged[f];
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&m.0), bits(&st.0), "tooth {f}: positions");
            assert_eq!(m.1, st.1, "tooth {f}: indices");
            assert_eq!(m.2, st.2, "tooth {f}: sources");
        }
    }
    // The report's timings come from the stages: no registration time, cut and stitch timed.
    let mut len = 0usize;
    // SAFETY: live session; size query then copy into a buffer of that size + 1.
    let json = unsafe {
        call(
            &s,
            toothfuse_session_report_json(s.0, ptr::null_mut(), 0, &mut len),
        );
        let mut buf = vec![0 as std::ffi::c_char; len + 1];
        call(
            &s,
            toothfuse_session_report_json(s.0, buf.as_mut_ptr(), len + 1, &mut len),
        );
        std::ffi::CStr::from_ptr(buf.as_ptr())
            .to_str()
            .unwrap()
            .to_owned()
    };
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let t = |k: &str| v["timing_ms"][k].as_f64().unwrap();
    assert_eq!(t("register"), 0.0);
    assert!(t("cut") > 0.0 && t("stitch") > 0.0, "{}", v["timing_ms"]);
    // (to 1e-12 relative: the JSON reader may round the last bit)
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    assert!(
        close(t("fuse"), t("cut") + t("stitch")),
        "{}",
        v["timing_ms"]
    );
    assert!(
        close(t("total"), t("cut") + t("stitch")),
        "{}",
        v["timing_ms"]
    );
    assert_eq!(v["teeth"].as_array().unwrap().len(), staged.len());
    // Per tooth, the band builds: at least one made; reused ones only after one made.
    for tooth in v["teeth"].as_array().unwrap() {
        let (made, reused) = (&tooth["band_builds"], &tooth["band_builds_reused"]);
        let (made, reused) = (made.as_u64().unwrap(), reused.as_u64().unwrap());
        assert!(made >= 1 && (reused == 0 || made > 1), "{tooth}");
    }
    // Stitching the same cut again gives the same meshes.
    // SAFETY: as above.
    unsafe { call(&s, toothfuse_session_stitch(s.0, ptr::null())) };
    assert_eq!(all_fused(&s), staged);

    for (&fdi, (pos, tris, src)) in &staged {
        let (rv, rt, lp) = cut_root(&s, fdi);
        let boundary = single_boundary_loop(&rt, fdi);
        assert!(
            cyclic_equal(&boundary, &lp),
            "tooth {fdi}: cut loop is not the root's boundary loop"
        );
        assert!(lp.len() >= 3 && rt.len() >= 3);
        // The root is one connected disk: V - E + F = 1.
        let nv = rv.len() / 3;
        let used: BTreeSet<u32> = rt.iter().copied().collect();
        assert_eq!(used.len(), nv, "tooth {fdi}: unused root vertices");
        let edges = (rt.len() + lp.len()) / 2;
        assert_eq!(
            nv as i64 - edges as i64 + (rt.len() / 3) as i64,
            1,
            "tooth {fdi}: not a disk"
        );
        // The fused tooth's CBCT part is exactly the cut root: same vertices bit for bit, in
        // order, and the root's triangles (offset) among the fused triangles. So nothing of
        // the CBCT crown side is left: crown + band + this root is the whole fused tooth.
        let cbct: Vec<u64> = pos
            .chunks_exact(3)
            .zip(src)
            .filter(|(_, s)| **s == TOOTHFUSE_SOURCE_CBCT)
            .flat_map(|(c, _)| c.iter().map(|x| x.to_bits()))
            .collect();
        let root: Vec<u64> = rv.iter().map(|x| x.to_bits()).collect();
        assert_eq!(cbct, root, "tooth {fdi}: fused CBCT part vs cut root");
        let off = src
            .iter()
            .position(|&x| x == TOOTHFUSE_SOURCE_CBCT)
            .unwrap() as u32;
        assert!(
            src[off as usize..]
                .iter()
                .all(|&x| x == TOOTHFUSE_SOURCE_CBCT)
        );
        let fused_tris: BTreeSet<[u32; 3]> =
            tris.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        for t in rt.chunks_exact(3) {
            assert!(
                fused_tris.contains(&[t[0] + off, t[1] + off, t[2] + off]),
                "tooth {fdi}: root triangle {t:?} not in the fused mesh"
            );
        }
        // The band (every other triangle) meets the root only on its cut loop.
        let loop_set: BTreeSet<u32> = lp.iter().map(|&v| v + off).collect();
        assert!(
            fused_tris
                .iter()
                .filter(|t| t.iter().any(|&v| v < off))
                .all(|t| t.iter().all(|&v| v < off || loop_set.contains(&v))),
            "tooth {fdi}: the band meets the root only on its cut loop"
        );
    }
}

#[test]
fn stage_order_and_dropped_cut_are_wrong_state() {
    let p = phantom(5);
    let s = Session::new();
    add_phantom(&s, &p);
    let (mut nv, mut ni, mut nl) = (0usize, 0usize, 0usize);
    // SAFETY: live session or NULL (refused), valid or NULL out pointers as
    // stated, buffers of the stated sizes.
    unsafe {
        assert_eq!(
            toothfuse_session_cut(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        assert!(s.error().contains("no registration"), "{}", s.error());
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        assert!(s.error().contains("no cut"), "{}", s.error());
        assert_eq!(
            toothfuse_session_cut(ptr::null_mut(), ptr::null()),
            toothfuse_status::NullParameter
        );
        assert_eq!(
            toothfuse_session_stitch(ptr::null_mut(), ptr::null()),
            toothfuse_status::NullParameter
        );
        call(&s, toothfuse_session_register(s.0, ptr::null()));
        // Registered but not cut: still no stitch, no cut getters.
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        assert_eq!(
            toothfuse_session_cut_size(s.0, 11, &mut nv, &mut ni, &mut nl),
            toothfuse_status::WrongState
        );
        let bad = toothfuse_options {
            preset: 7,
            ..toothfuse_options::default()
        };
        assert_eq!(
            toothfuse_session_cut(s.0, &bad),
            toothfuse_status::InvalidArgument
        );
        call(&s, toothfuse_session_cut(s.0, ptr::null()));
    }
    let cut = teeth(&s, toothfuse_session_cut_teeth);
    assert!(cut.len() >= 3, "{cut:?}");
    let fdi = cut[0];
    // SAFETY: as above.
    unsafe {
        // NULL outputs, short buffers, a tooth that was not cut.
        assert_eq!(
            toothfuse_session_cut_size(s.0, fdi, ptr::null_mut(), &mut ni, &mut nl),
            toothfuse_status::NullParameter
        );
        assert!(s.error().contains("vertex_count_out"), "{}", s.error());
        assert_eq!(
            toothfuse_session_cut_size(s.0, fdi, &mut nv, &mut ni, ptr::null_mut()),
            toothfuse_status::NullParameter
        );
        call(
            &s,
            toothfuse_session_cut_size(s.0, fdi, &mut nv, &mut ni, &mut nl),
        );
        let mut v = vec![0f64; 3 * nv];
        assert_eq!(
            toothfuse_session_copy_cut_vertices(
                s.0,
                fdi,
                v.as_mut_ptr().cast(),
                nv - 1,
                24,
                TOOTHFUSE_SCALAR_FLOAT64
            ),
            toothfuse_status::BufferTooSmall
        );
        assert!(
            s.error().starts_with(&format!("cut tooth {fdi}: ")),
            "{}",
            s.error()
        );
        assert!(v.iter().all(|&x| x == 0.0), "nothing written");
        assert_eq!(
            toothfuse_session_copy_cut_vertices(
                s.0,
                fdi,
                v.as_mut_ptr().cast(),
                nv,
                8,
                TOOTHFUSE_SCALAR_FLOAT64
            ),
            toothfuse_status::InvalidArgument
        );
        assert_eq!(
            toothfuse_session_copy_cut_vertices(
                s.0,
                fdi,
                ptr::null_mut(),
                nv,
                24,
                TOOTHFUSE_SCALAR_FLOAT64
            ),
            toothfuse_status::NullParameter
        );
        let mut t = vec![7u32; ni];
        assert_eq!(
            toothfuse_session_copy_cut_indices(s.0, fdi, t.as_mut_ptr(), ni - 1),
            toothfuse_status::BufferTooSmall
        );
        assert!(
            s.error().contains(&format!("cut tooth {fdi}")),
            "{}",
            s.error()
        );
        assert!(t.iter().all(|&x| x == 7));
        assert_eq!(
            toothfuse_session_copy_cut_indices(s.0, fdi, ptr::null_mut(), ni),
            toothfuse_status::NullParameter
        );
        let mut lp = vec![7u32; nl];
        assert_eq!(
            toothfuse_session_copy_cut_loop(s.0, fdi, lp.as_mut_ptr(), nl - 1),
            toothfuse_status::BufferTooSmall
        );
        assert!(lp.iter().all(|&x| x == 7));
        let mut few = [0i32; 1];
        let mut n = 0usize;
        assert_eq!(
            toothfuse_session_cut_teeth(s.0, few.as_mut_ptr(), 1, &mut n),
            toothfuse_status::BufferTooSmall
        );
        assert_eq!(
            toothfuse_session_cut_size(s.0, 48, &mut nv, &mut ni, &mut nl),
            toothfuse_status::MissingData
        );
        assert!(s.error().contains("tooth 48 was not cut"), "{}", s.error());
        assert_eq!(
            toothfuse_session_cut_size(s.0, 19, &mut nv, &mut ni, &mut nl),
            toothfuse_status::InvalidArgument
        );
        // Removing a tooth drops the cut (and the registration): stitch and getters refuse.
        call(
            &s,
            toothfuse_session_remove_tooth(s.0, TOOTHFUSE_MODALITY_CBCT, fdi),
        );
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        assert!(s.error().contains("no cut"), "{}", s.error());
        assert_eq!(
            toothfuse_session_cut_size(s.0, cut[1], &mut nv, &mut ni, &mut nl),
            toothfuse_status::WrongState
        );
        assert_eq!(
            toothfuse_session_cut(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        // Adding the tooth back (or replacing it) drops the cut again.
        let m = &p.cbct[&(fdi as u8)];
        let v: Vec<f64> = m.positions.iter().flat_map(|q| q.to_array()).collect();
        let t: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        call(&s, s.add(TOOTHFUSE_MODALITY_CBCT, fdi, &v, &t));
        call(&s, toothfuse_session_register(s.0, ptr::null()));
        call(&s, toothfuse_session_cut(s.0, ptr::null()));
        assert_eq!(teeth(&s, toothfuse_session_cut_teeth), cut);
        call(&s, s.add(TOOTHFUSE_MODALITY_CBCT, fdi, &v, &t));
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        // A new registration drops the cut too; so does a one-call fuse.
        call(&s, toothfuse_session_register(s.0, ptr::null()));
        call(&s, toothfuse_session_cut(s.0, ptr::null()));
        call(&s, toothfuse_session_register(s.0, ptr::null()));
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
        call(&s, toothfuse_session_cut(s.0, ptr::null()));
        call(&s, toothfuse_session_fuse(s.0, ptr::null()));
        assert_eq!(
            toothfuse_session_stitch(s.0, ptr::null()),
            toothfuse_status::WrongState
        );
    }
}
