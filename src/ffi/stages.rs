//! The fusion in two stages through the C ABI: `toothfuse_session_cut` (crown removal with the
//! session's last registration) then `toothfuse_session_stitch` (band, assembly, quality), and
//! the cut stage's per-tooth results for hosts that inspect or draw the cut: the CBCT root that
//! is kept and its cut loop. The stitched meshes are read with the fused getters (`ffi::fuse`).
//!
//! Stages: register → cut → stitch gives the same fused meshes, bit for bit, as
//! `toothfuse_session_fuse_registered` after the same registration (and as the one-call
//! `toothfuse_session_fuse` with the same options).

use super::boundary::{Failure, FfiResult, check_out, copy_out, ffi_panic_boundary, write_out};
use super::mesh::{toothfuse_scalar, write_vertices};
use super::register::{copy_fdis, toothfuse_options, with_options};
use super::session::{toothfuse_session, with_session};
use super::status::toothfuse_status;
use crate::arch::check_fdi;
use crate::fuse::CutTooth;
use crate::session::Session;
use std::ffi::c_void;

/// Crown removal with the session's last registration (`toothfuse_session_register`, or an
/// earlier fuse): each IOS crown present in both modalities is repaired and moved into the
/// output frame, and its CBCT tooth cut along the IOS gingival margin, keeping the root (paper
/// section 2.3.1; `options`: NULL = defaults, only its fusion settings are used, the output
/// frame is the registration's). The cut is kept on the session for `toothfuse_session_stitch`
/// (replacing an earlier cut; fused results are kept) until the teeth change or a new register
/// or fuse. A tooth whose cut fails is listed by `toothfuse_session_skipped` with the reason.
/// WRONG_STATE without a registration; on any failure the previous results are kept.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_cut(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contracts on `session` and `options`.
        unsafe {
            with_options(session, options, |s, o| {
                s.cut(o)?;
                Ok(())
            })
        }
    }
}

/// Stitching on the held cut: per cut tooth, the band between the IOS margin and the CBCT cut
/// loop, crown + band + root assembled into one closed, manifold mesh (paper Algorithm 1;
/// `options`: NULL = defaults, its cut settings are not used: the cut is done). The fused
/// results replace earlier ones and are read with the fused getters; the cut stays, so it can be
/// stitched again. WRONG_STATE without a cut (none yet, or dropped by a change of teeth, a new
/// register or fuse); on any failure the previous results are kept.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_stitch(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contracts on `session` and `options`.
        unsafe {
            with_options(session, options, |s, o| {
                s.stitch(o)?;
                Ok(())
            })
        }
    }
}

/// Copies the FDI numbers of the cut teeth, ascending, into `fdi_out` (room for `capacity`) and
/// writes how many to `*count_out`; BUFFER_TOO_SMALL (nothing written) when `capacity` is below
/// the count (52 always suffices). WRONG_STATE without a cut.
///
/// # Safety
/// `session` must be NULL or a live session; `fdi_out` must have room for `capacity` `int32_t`;
/// `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_cut_teeth(
    session: *const toothfuse_session,
    fdi_out: *mut i32,
    capacity: usize,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let fdis: Vec<u8> = s.cut_result()?.jaw.teeth.keys().copied().collect();
            // SAFETY: forwarded contract on the outputs.
            unsafe { copy_fdis(&fdis, fdi_out, capacity, count_out) }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// The cut tooth `fdi`; WRONG_STATE without a cut, MISSING_DATA (with the reason) for a tooth
/// that was not cut.
fn cut_tooth(s: &Session, fdi: i32) -> FfiResult<&CutTooth> {
    let key = check_fdi(fdi)?;
    let jaw = &s.cut_result()?.jaw;
    jaw.teeth.get(&key).ok_or_else(|| {
        let why = jaw.failed.iter().find(|(k, _)| *k == key).map_or_else(
            || "it is not in both modalities".to_string(),
            |(_, e)| e.to_string(),
        );
        Failure::new(
            toothfuse_status::MissingData,
            format!("tooth {fdi} was not cut: {why}"),
        )
    })
}

/// Writes the sizes of the cut root of tooth `fdi`: its vertex count, index count (3 per
/// triangle) and the length of its cut loop (its one boundary loop, where the band meets the
/// root). WRONG_STATE without a cut; MISSING_DATA for a tooth that was not cut.
///
/// # Safety
/// `session` must be NULL or a live session; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_cut_size(
    session: *const toothfuse_session,
    fdi: i32,
    vertex_count_out: *mut usize,
    index_count_out: *mut usize,
    loop_count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(vertex_count_out, "vertex_count_out")?;
            check_out(index_count_out, "index_count_out")?;
            check_out(loop_count_out, "loop_count_out")?;
            let root = cut_tooth(s, fdi)?.root();
            // SAFETY: forwarded contract on the outputs (checked non-NULL above).
            unsafe {
                write_out(vertex_count_out, root.root.positions.len(), "vertex_count_out")?;
                write_out(index_count_out, 3 * root.root.triangles.len(), "index_count_out")?;
                write_out(loop_count_out, root.cut_loop.len(), "loop_count_out")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the vertices of the cut root of tooth `fdi` (output frame; the CBCT vertices kept, at
/// their positions under CBCT→output, exactly the fused mesh's CBCT-source vertices) as
/// `toothfuse_session_copy_vertices` does (strided, float or double; BUFFER_TOO_SMALL when
/// `vertex_capacity` is below the count).
///
/// # Safety
/// `session` must be NULL or a live session; `vertices_out` must hold
/// `(vertex_capacity - 1) * stride_bytes + 3 * sizeof(scalar)` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_cut_vertices(
    session: *const toothfuse_session,
    fdi: i32,
    vertices_out: *mut c_void,
    vertex_capacity: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let root = &cut_tooth(s, fdi)?.root().root;
            // SAFETY: forwarded contract on `vertices_out`.
            unsafe {
                write_vertices(&root.positions, vertices_out, vertex_capacity, stride_bytes, scalar)
            }
            .map_err(|f| Failure::new(f.status, format!("cut tooth {fdi}: {}", f.message)))
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the triangle indices of the cut root of tooth `fdi`, 3 per triangle, outward
/// (counter-clockwise seen from outside); BUFFER_TOO_SMALL (nothing written) when
/// `index_capacity` is below the index count.
///
/// # Safety
/// `session` must be NULL or a live session; `indices_out` room for `index_capacity` `uint32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_cut_indices(
    session: *const toothfuse_session,
    fdi: i32,
    indices_out: *mut u32,
    index_capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let tris = cut_tooth(s, fdi)?.root().root.triangles.as_flattened();
            // SAFETY: forwarded contract on `indices_out`.
            unsafe {
                copy_out(tris, indices_out, index_capacity, "indices_out", &format!("cut tooth {fdi}"), "indices")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the cut loop of tooth `fdi`: the root's one boundary loop as root vertex indices, in
/// order (root surface on the left seen from outside); BUFFER_TOO_SMALL (nothing written) when
/// `capacity` is below the loop length.
///
/// # Safety
/// `session` must be NULL or a live session; `loop_out` room for `capacity` `uint32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_cut_loop(
    session: *const toothfuse_session,
    fdi: i32,
    loop_out: *mut u32,
    capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let lp = cut_tooth(s, fdi)?.cut_loop();
            // SAFETY: forwarded contract on `loop_out`.
            unsafe {
                copy_out(lp, loop_out, capacity, "loop_out", &format!("cut tooth {fdi}"), "loop vertices")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}
