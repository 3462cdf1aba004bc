//! Fuzzes the C ABI as a host uses it: a tiny labeled jaw, mutated by the input (moved, NaN or
//! huge vertices, bad indices, dropped triangles, wrong labels or FDI numbers, scaled or mirrored
//! scans, float or double with padded strides, face labels, repair on, bad option enums, short
//! vertex counts), is added with `toothfuse_session_add_jaw` / `toothfuse_session_add_tooth`,
//! fused with `toothfuse_session_fuse`, and every fused mesh is copied out. Any input must give
//! statuses and messages, never a panic (the panic hook aborts even on a caught panic), abort,
//! out-of-bounds access or hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, c_void};
use toothfuse::ffi::*;
use toothfuse_fuzz::jaw::{Call, Jaw, mutate};

/// Vertices as the host's buffer: float or double, `pad` bytes after each vertex.
fn vertex_buffer(v: &[f64], call: &Call) -> (Vec<u8>, usize, toothfuse_scalar) {
    let (size, scalar) = if call.float32 {
        (4, TOOTHFUSE_SCALAR_FLOAT32)
    } else {
        (8, TOOTHFUSE_SCALAR_FLOAT64)
    };
    let stride = 3 * size + call.pad;
    let mut out = Vec::with_capacity(v.len() / 3 * stride);
    for p in v.chunks_exact(3) {
        for &x in p {
            if call.float32 {
                out.extend((x as f32).to_ne_bytes());
            } else {
                out.extend(x.to_ne_bytes());
            }
        }
        out.extend(std::iter::repeat_n(0xAB, call.pad));
    }
    (out, stride, scalar)
}

/// The last error is always a valid C string.
fn last_error(s: *const toothfuse_session) -> usize {
    // SAFETY: live session; the string is read before the next call.
    unsafe { CStr::from_ptr(toothfuse_session_last_error(s)) }
        .to_bytes()
        .len()
}

/// Copies out every fused mesh with buffers of exactly the announced sizes.
fn copy_fused(s: *mut toothfuse_session) {
    let mut fdis = [0i32; 52];
    let mut n = 0usize;
    // SAFETY: live session, room for 52.
    if unsafe { toothfuse_session_fused_teeth(s, fdis.as_mut_ptr(), 52, &mut n) }
        != toothfuse_status::Ok
    {
        return;
    }
    // Each fused tooth, then the whole fused jaw (fdi 0) when any tooth was fused.
    let whole: &[i32] = if n > 0 { &[0] } else { &[] };
    for &fdi in fdis[..n].iter().chain(whole) {
        let (mut nv, mut ni) = (0usize, 0usize);
        // SAFETY: live session, valid out pointers.
        let st = unsafe { toothfuse_session_fused_size(s, fdi, &mut nv, &mut ni) };
        assert_eq!(st, toothfuse_status::Ok, "size of fused {fdi}");
        let mut v = vec![0f64; 3 * nv];
        let mut i = vec![0u32; ni];
        let mut src = vec![0u8; nv];
        // SAFETY: buffers sized as announced.
        unsafe {
            let st = toothfuse_session_copy_fused_vertices(
                s,
                fdi,
                v.as_mut_ptr().cast::<c_void>(),
                nv,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
            );
            assert_eq!(st, toothfuse_status::Ok);
            assert_eq!(
                toothfuse_session_copy_fused_indices(s, fdi, i.as_mut_ptr(), ni),
                toothfuse_status::Ok
            );
            assert_eq!(
                toothfuse_session_copy_fused_sources(s, fdi, src.as_mut_ptr(), nv),
                toothfuse_status::Ok
            );
        }
        assert!(
            v.iter().all(|x| x.is_finite()),
            "fused {fdi}: non-finite vertex"
        );
        assert!(
            i.iter().all(|&k| (k as usize) < nv),
            "fused {fdi}: index out of range"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let mut jaw = Jaw::new();
    let call = mutate(&mut jaw, data);
    let mut s = std::ptr::null_mut();
    // SAFETY: valid out pointer.
    assert_eq!(
        unsafe { toothfuse_session_new(&mut s) },
        toothfuse_status::Ok
    );
    if call.repair {
        // SAFETY: live session.
        unsafe { toothfuse_session_set_ios_repair(s, true, 0.2) };
    }
    let (vb, stride, scalar) = vertex_buffer(&jaw.ios_vertices, &call);
    let nv = (jaw.ios_vertices.len() / 3).saturating_sub(call.vertex_count_cut);
    let (labels, domain) = if call.face_labels {
        let l: Vec<i32> = jaw
            .ios_indices
            .chunks_exact(3)
            .map(|t| jaw.ios_labels.get(t[0] as usize).copied().unwrap_or(-1))
            .collect();
        (l, TOOTHFUSE_LABEL_DOMAIN_FACE)
    } else {
        (jaw.ios_labels.clone(), TOOTHFUSE_LABEL_DOMAIN_VERTEX)
    };
    // SAFETY: buffers hold at least the announced counts (nv never exceeds the buffer).
    let st = unsafe {
        toothfuse_session_add_jaw(
            s,
            TOOTHFUSE_MODALITY_IOS,
            vb.as_ptr().cast(),
            nv,
            stride,
            scalar,
            jaw.ios_indices.as_ptr(),
            jaw.ios_indices.len(),
            labels.as_ptr(),
            labels.len(),
            domain,
        )
    };
    if st != toothfuse_status::Ok {
        assert!(last_error(s) > 0, "failure without a message");
    }
    for (fdi, v, idx) in &jaw.cbct {
        let (vb, stride, scalar) = vertex_buffer(v, &call);
        // SAFETY: buffers hold the announced counts.
        let st = unsafe {
            toothfuse_session_add_tooth(
                s,
                TOOTHFUSE_MODALITY_CBCT,
                *fdi,
                vb.as_ptr().cast(),
                v.len() / 3,
                stride,
                scalar,
                idx.as_ptr(),
                idx.len(),
            )
        };
        if st != toothfuse_status::Ok {
            assert!(last_error(s) > 0, "failure without a message");
        }
    }
    let mut opts = toothfuse_options::default();
    // SAFETY: valid out pointer.
    assert_eq!(
        unsafe { toothfuse_options_default(&mut opts) },
        toothfuse_status::Ok
    );
    opts.preset = call.preset;
    opts.frame = call.frame;
    // SAFETY: live session, valid options.
    let st = unsafe { toothfuse_session_fuse(s, &opts) };
    if st == toothfuse_status::Ok {
        copy_fused(s);
    } else {
        assert!(last_error(s) > 0, "failure without a message");
    }
    // SAFETY: created above, freed once.
    unsafe { toothfuse_session_free(s) };
});
