//! Unit tests of the raw-pointer layer on tiny meshes, small enough for Miri
//! (`cargo +nightly miri test --lib ffi::`, run by scripts/check_sanitizers.sh): unaligned and
//! strided float/double input, borrowed views, copy-out at the exact capacity and one short,
//! NULL and misaligned parameters, the options struct size, labeled jaws split into teeth, and
//! the progress hook calling the host back with its pointer.

use super::*;
use std::ffi::{CStr, c_void};
use std::ptr;

/// A tetrahedron, outward: 4 vertices, 4 triangles.
const TET: [[f64; 3]; 4] = [[0., 0., 0.], [2., 0., 0.], [0., 2., 0.], [0., 0., 2.]];
const TET_IDX: [u32; 12] = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];

struct S(*mut toothfuse_session);

impl S {
    fn new() -> S {
        let mut p = ptr::null_mut();
        // SAFETY: valid out pointer.
        let st = unsafe { toothfuse_session_new(&mut p) };
        assert_eq!(st, toothfuse_status::Ok);
        S(p)
    }
    fn error(&self) -> String {
        // SAFETY: live session; copied at once.
        unsafe { CStr::from_ptr(toothfuse_session_last_error(self.0)) }
            .to_string_lossy()
            .into_owned()
    }
}

impl Drop for S {
    fn drop(&mut self) {
        // SAFETY: created by S::new, freed once.
        unsafe { toothfuse_session_free(self.0) }
    }
}

/// `TET` as float with `pad` bytes after each vertex, starting one byte into the buffer (so the
/// floats are misaligned, which the ABI allows).
fn tet_f32_unaligned(pad: usize) -> (Vec<u8>, usize) {
    let stride = 12 + pad;
    let mut b = vec![0xEEu8; 1];
    for p in TET {
        for c in p {
            b.extend((c as f32).to_ne_bytes());
        }
        b.extend(std::iter::repeat_n(0xEE, pad));
    }
    (b, stride)
}

#[test]
fn unaligned_strided_float_input_round_trips_through_view_and_copies() {
    let s = S::new();
    let (buf, stride) = tet_f32_unaligned(5);
    // SAFETY: live session; 4 vertices at `stride` from byte 1 of `buf`; 12 indices.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            36,
            buf.as_ptr().add(1).cast::<c_void>(),
            4,
            stride,
            TOOTHFUSE_SCALAR_FLOAT32,
            TET_IDX.as_ptr(),
            12,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut view = toothfuse_mesh_view {
        positions: ptr::null(),
        vertex_count: 0,
        indices: ptr::null(),
        index_count: 0,
    };
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_mesh_view(s.0, TOOTHFUSE_MODALITY_CBCT, 36, &mut view) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!((view.vertex_count, view.index_count), (4, 12));
    // SAFETY: the view borrows the session's arrays, alive and unchanged here.
    let (pos, idx) = unsafe {
        (
            std::slice::from_raw_parts(view.positions, 12),
            std::slice::from_raw_parts(view.indices, 12),
        )
    };
    assert_eq!(pos, TET.as_flattened());
    assert_eq!(idx, TET_IDX);
    // Copy out as float into a padded buffer: exact capacity fills it, padding untouched.
    let mut out = vec![0x55u8; 3 * 16 + 12];
    // SAFETY: room for 4 vertices at stride 16.
    let st = unsafe {
        toothfuse_session_copy_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            36,
            out.as_mut_ptr().cast(),
            4,
            16,
            TOOTHFUSE_SCALAR_FLOAT32,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    for (i, p) in TET.iter().enumerate() {
        for (k, &c) in p.iter().enumerate() {
            let o = i * 16 + 4 * k;
            assert_eq!(
                f32::from_ne_bytes(out[o..o + 4].try_into().unwrap()),
                c as f32
            );
        }
        if i < 3 {
            assert_eq!(out[i * 16 + 12..i * 16 + 16], [0x55; 4], "padding written");
        }
    }
}

#[test]
fn short_buffers_write_nothing_and_exact_ones_are_filled() {
    let s = S::new();
    // SAFETY: live session, buffers sized as announced.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            TET.as_ptr().cast(),
            4,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            TET_IDX.as_ptr(),
            12,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut idx = [7u32; 12];
    // SAFETY: room for 11 (announced) of 12.
    let st = unsafe {
        toothfuse_session_copy_indices(s.0, TOOTHFUSE_MODALITY_CBCT, 11, idx.as_mut_ptr(), 11)
    };
    assert_eq!(st, toothfuse_status::BufferTooSmall);
    assert_eq!(idx, [7; 12], "a short buffer is left untouched");
    assert!(s.error().contains("room for 11"), "{}", s.error());
    // SAFETY: room for 12.
    let st = unsafe {
        toothfuse_session_copy_indices(s.0, TOOTHFUSE_MODALITY_CBCT, 11, idx.as_mut_ptr(), 12)
    };
    assert_eq!(st, toothfuse_status::Ok);
    assert_eq!(idx, TET_IDX);
    let mut v = [0f64; 12];
    // SAFETY: room for 3 (announced) of 4 vertices.
    let st = unsafe {
        toothfuse_session_copy_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_mut_ptr().cast(),
            3,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
        )
    };
    assert_eq!(st, toothfuse_status::BufferTooSmall);
    assert_eq!(v, [0.0; 12]);
    let mut fdis = [0i32; 2];
    let mut n = 99usize;
    // SAFETY: room for 2.
    let st = unsafe {
        toothfuse_session_list_teeth(s.0, TOOTHFUSE_MODALITY_CBCT, fdis.as_mut_ptr(), 2, &mut n)
    };
    assert_eq!(st, toothfuse_status::Ok);
    assert_eq!((n, fdis[0]), (1, 11));
}

#[test]
fn null_misaligned_and_oversized_parameters_are_refused() {
    let s = S::new();
    // SAFETY: NULL with a count is checked before any read.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            ptr::null(),
            4,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            TET_IDX.as_ptr(),
            12,
        )
    };
    assert_eq!(st, toothfuse_status::NullParameter);
    assert!(s.error().contains("vertices"), "{}", s.error());
    // Indices must be 4-byte aligned: one byte into the array is refused before any read.
    // SAFETY: the misaligned pointer is only checked, never dereferenced.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            TET.as_ptr().cast(),
            4,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            TET_IDX.as_ptr().cast::<u8>().wrapping_add(1).cast::<u32>(),
            12,
        )
    };
    assert_eq!(st, toothfuse_status::InvalidArgument, "{}", s.error());
    // A count whose byte size overflows is refused, never read.
    // SAFETY: only checked.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            TET.as_ptr().cast(),
            usize::MAX / 8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            TET_IDX.as_ptr(),
            12,
        )
    };
    assert_ne!(st, toothfuse_status::Ok);
    // A NULL session is a status, not a crash; so is a NULL out pointer.
    let mut n = 0usize;
    // SAFETY: NULL session is allowed.
    let st = unsafe { toothfuse_session_tooth_count(ptr::null(), TOOTHFUSE_MODALITY_IOS, &mut n) };
    assert_eq!(st, toothfuse_status::NullParameter);
    // SAFETY: live session, NULL out pointer is checked.
    let st = unsafe { toothfuse_session_tooth_count(s.0, TOOTHFUSE_MODALITY_IOS, ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    // The session held nothing through all of that.
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_tooth_count(s.0, TOOTHFUSE_MODALITY_CBCT, &mut n) };
    assert_eq!((st, n), (toothfuse_status::Ok, 0));
}

#[test]
fn options_struct_size_is_checked_before_reading_fields() {
    let s = S::new();
    let mut o = toothfuse_options::default();
    // SAFETY: valid out pointer.
    let st = unsafe { toothfuse_options_default(&mut o) };
    assert_eq!(st, toothfuse_status::Ok);
    assert_eq!(o.struct_size, std::mem::size_of::<toothfuse_options>());
    o.struct_size = 4;
    // SAFETY: live session, valid options.
    let st = unsafe { toothfuse_session_register(s.0, &o) };
    assert_eq!(st, toothfuse_status::InvalidArgument);
    assert!(s.error().contains("struct_size 4"), "{}", s.error());
}

#[test]
fn labeled_jaw_is_split_into_teeth_with_their_source_vertices() {
    let s = S::new();
    // Two open 5 mm squares (crown-sized, so the unit check passes), labels 11 and 21 (one per
    // vertex); vertex 8 is gingiva (label 0).
    let v: [f64; 27] = [
        0., 0., 0., 5., 0., 0., 5., 5., 0., 0., 5., 0., //
        25., 0., 0., 30., 0., 0., 30., 5., 0., 25., 5., 0., //
        45., 45., 45.,
    ];
    let idx: [u32; 12] = [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7];
    let labels: [i32; 9] = [11, 11, 11, 11, 21, 21, 21, 21, 0];
    // SAFETY: live session, buffers sized as announced.
    let st = unsafe {
        toothfuse_session_add_jaw(
            s.0,
            TOOTHFUSE_MODALITY_IOS,
            v.as_ptr().cast(),
            9,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            idx.as_ptr(),
            12,
            labels.as_ptr(),
            9,
            TOOTHFUSE_LABEL_DOMAIN_VERTEX,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut src = [0u32; 4];
    // SAFETY: room for 4.
    let st = unsafe {
        toothfuse_session_copy_source_vertices(s.0, TOOTHFUSE_MODALITY_IOS, 21, src.as_mut_ptr(), 4)
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(src, [4, 5, 6, 7]);
    // A label count that does not match the domain is refused; the session keeps both teeth.
    // SAFETY: as above, with a shorter announced label count.
    let st = unsafe {
        toothfuse_session_add_jaw(
            s.0,
            TOOTHFUSE_MODALITY_IOS,
            v.as_ptr().cast(),
            9,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            idx.as_ptr(),
            12,
            labels.as_ptr(),
            8,
            TOOTHFUSE_LABEL_DOMAIN_VERTEX,
        )
    };
    assert_ne!(st, toothfuse_status::Ok);
    let mut n = 0usize;
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_tooth_count(s.0, TOOTHFUSE_MODALITY_IOS, &mut n) };
    assert_eq!((st, n), (toothfuse_status::Ok, 2));
}

/// The thread cap: NULL refused; any value accepted and kept by the session; calls under a cap
/// of one run on the calling thread and still succeed.
#[test]
fn thread_cap_is_set_per_session_and_null_is_refused() {
    // SAFETY: NULL is allowed and refused.
    let st = unsafe { toothfuse_session_set_max_threads(ptr::null_mut(), 1) };
    assert_eq!(st, toothfuse_status::NullParameter);
    let s = S::new();
    for n in [0, 1, 4, u32::MAX, 1] {
        // SAFETY: live session.
        let st = unsafe { toothfuse_session_set_max_threads(s.0, n) };
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    }
    // SAFETY: live session; 4 double vertices, 12 indices.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            36,
            TET.as_ptr().cast::<c_void>(),
            4,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            TET_IDX.as_ptr(),
            12,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(crate::par::max_threads(), 0, "the cap ends with the call");
}

/// The progress hook as the session calls it: the host's callback gets its own pointer back
/// with each report on the calling thread, and a nonzero answer cancels (small enough for Miri).
#[test]
fn progress_hook_passes_the_hosts_pointer_and_a_nonzero_answer_cancels() {
    unsafe extern "C" fn count(data: *mut c_void, stage: u32, done: usize, total: usize) -> i32 {
        // SAFETY: the test passes a live `[usize; 4]` it owns for the call.
        let seen = unsafe { &mut *data.cast::<[usize; 4]>() };
        *seen = [seen[0] + 1, stage as usize, done, total];
        i32::from(done >= 1)
    }
    // SAFETY: NULL is allowed and refused.
    let st =
        unsafe { toothfuse_session_set_progress(ptr::null_mut(), Some(count), ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    let mut seen = [0usize; 4];
    let s = S::new();
    // SAFETY: live session; `seen` outlives every call made while the hook is set.
    let st = unsafe {
        toothfuse_session_set_progress(s.0, Some(count), ptr::from_mut(&mut seen).cast())
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let hook = s_hook(&s);
    use crate::progress::{Stage, advance, cancelled, start};
    super::progress::with_hook(hook, || {
        start(Stage::Cut, 2);
        assert!(!cancelled());
        advance();
        assert!(cancelled());
    });
    assert_eq!(seen, [2, TOOTHFUSE_STAGE_CUT as usize, 1, 2]);
    // Removed: nothing more is reported.
    // SAFETY: live session.
    let st = unsafe { toothfuse_session_set_progress(s.0, None, ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::Ok);
    super::progress::with_hook(s_hook(&s), || start(Stage::Stitch, 1));
    assert_eq!(seen[0], 2);
}

/// The progress hook held by the session behind `s`.
fn s_hook(s: &S) -> Option<super::progress::Hook> {
    // SAFETY: a live session, only read here.
    unsafe { &*s.0 }.progress.get()
}
