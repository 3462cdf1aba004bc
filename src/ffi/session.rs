//! `toothfuse_session`: the opaque handle, its lifetime, last error and poisoning, and adding,
//! removing and listing teeth.

use super::boundary::{
    Failure, FfiResult, bytes_in, check_out, ffi_panic_boundary, panic_message, slice_in,
    slice_out, write_out,
};
use super::mesh::{decode_scalar, toothfuse_scalar};
use super::status::toothfuse_status;
use crate::TriMesh;
use crate::mesh::{LabelDomain, VertexBuffer};
use crate::session::{Modality, Session};
use std::cell::{Cell, RefCell};
use std::ffi::{CString, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Which scan a tooth comes from: one of the `TOOTHFUSE_MODALITY_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_modality = u32;
/// Intraoral scan: crowns only, open at the gingival margin; must be 2-manifold.
pub const TOOTHFUSE_MODALITY_IOS: toothfuse_modality = 0;
/// CBCT segmentation: whole teeth; must be closed and 2-manifold.
pub const TOOTHFUSE_MODALITY_CBCT: toothfuse_modality = 1;

/// Where the labels of a jaw mesh live: one of the `TOOTHFUSE_LABEL_DOMAIN_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_label_domain = u32;
/// One label per vertex; a triangle belongs to tooth L when all three of its vertices are
/// labeled L (triangles straddling two labels belong to none, so a crown ends at its margin).
pub const TOOTHFUSE_LABEL_DOMAIN_VERTEX: toothfuse_label_domain = 0;
/// One label per triangle.
pub const TOOTHFUSE_LABEL_DOMAIN_FACE: toothfuse_label_domain = 1;

/// A set of tooth meshes per modality, keyed by FDI number. Create with
/// `toothfuse_session_new`, destroy with `toothfuse_session_free`.
///
/// Thread safety: a session is NOT thread-safe. Every call on one session, including the
/// `const` queries (which record the last error), must be serialised by the caller. Distinct
/// sessions are independent and may be used from different threads at the same time.
#[allow(non_camel_case_types)]
pub struct toothfuse_session {
    pub(crate) core: Session,
    last_error: RefCell<CString>,
    poisoned: Cell<bool>,
    /// The cap on the threads of this session's calls (0: none), see
    /// `toothfuse_session_set_max_threads`.
    max_threads: Cell<usize>,
    /// The progress callback of this session's calls, see `toothfuse_session_set_progress`.
    pub(super) progress: Cell<Option<super::progress::Hook>>,
}

impl toothfuse_session {
    fn new() -> Self {
        Self {
            core: Session::new(),
            last_error: RefCell::new(CString::default()),
            poisoned: Cell::new(false),
            max_threads: Cell::new(0),
            progress: Cell::new(None),
        }
    }

    fn set_error(&self, message: &str) {
        let clean: Vec<u8> = message.bytes().filter(|&b| b != 0).collect();
        *self.last_error.borrow_mut() = CString::new(clean).unwrap_or_default();
    }

    /// Turns a body's outcome into a status, recording the message (cleared on success) and
    /// poisoning the session after a panic.
    fn finish(&self, outcome: std::thread::Result<FfiResult>) -> toothfuse_status {
        match outcome {
            Ok(Ok(())) => {
                self.set_error("");
                toothfuse_status::Ok
            }
            Ok(Err(f)) => {
                self.set_error(&f.message);
                f.status
            }
            Err(payload) => {
                self.poisoned.set(true);
                self.set_error(&format!(
                    "internal error (panic: {}); the session is poisoned, free it",
                    panic_message(payload.as_ref())
                ));
                toothfuse_status::Panic
            }
        }
    }

    fn check_poison(&self) -> FfiResult {
        if self.poisoned.get() {
            return Err(Failure::new(
                toothfuse_status::Poisoned,
                "the session was poisoned by an earlier internal error (panic); free it",
            ));
        }
        Ok(())
    }
}

/// Runs `f` on the session behind `ptr` for reading: NULL check, poison check, the session's
/// thread cap, panic capture, last-error bookkeeping.
///
/// # Safety
/// `ptr` must be NULL or a live session from `toothfuse_session_new`, not used concurrently.
pub(crate) unsafe fn with_session<F>(ptr: *const toothfuse_session, f: F) -> toothfuse_status
where
    F: FnOnce(&Session) -> FfiResult,
{
    // SAFETY: the caller guarantees `ptr` is NULL or a live, unaliased-for-writing session.
    let Some(s) = (unsafe { ptr.as_ref() }) else {
        return toothfuse_status::NullParameter;
    };
    if let Err(f) = s.check_poison() {
        return s.finish(Ok(Err(f)));
    }
    let cap = s.max_threads.get();
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        crate::par::with_max_threads(cap, || f(&s.core))
    }));
    s.finish(outcome)
}

/// Runs `f` on the session behind `ptr` for writing (see [`with_session`]).
///
/// # Safety
/// `ptr` must be NULL or a live session from `toothfuse_session_new`, used by no one else
/// during the call.
pub(crate) unsafe fn with_session_mut<F>(ptr: *mut toothfuse_session, f: F) -> toothfuse_status
where
    F: FnOnce(&mut Session) -> FfiResult,
{
    // SAFETY: the caller guarantees `ptr` is NULL or a live session nobody else uses now.
    let Some(s) = (unsafe { ptr.as_mut() }) else {
        return toothfuse_status::NullParameter;
    };
    if let Err(f) = s.check_poison() {
        return s.finish(Ok(Err(f)));
    }
    let (cap, hook) = (s.max_threads.get(), s.progress.get());
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        super::progress::with_hook(hook, || {
            crate::par::with_max_threads(cap, || f(&mut s.core))
        })
    }));
    s.finish(outcome)
}

/// Runs `set` on the session behind `ptr` to change one of its settings (the thread cap, the
/// progress callback): NULL check, poison check, last-error bookkeeping; no library work runs.
///
/// # Safety
/// `ptr` must be NULL or a live session from `toothfuse_session_new`, used by no one else
/// during the call.
pub(super) unsafe fn with_settings(
    ptr: *mut toothfuse_session,
    set: impl FnOnce(&toothfuse_session),
) -> toothfuse_status {
    // SAFETY: the caller guarantees `ptr` is NULL or a live session nobody else uses now.
    let Some(s) = (unsafe { ptr.as_ref() }) else {
        return toothfuse_status::NullParameter;
    };
    if let Err(f) = s.check_poison() {
        return s.finish(Ok(Err(f)));
    }
    set(s);
    s.finish(Ok(Ok(())))
}

/// Decodes a `toothfuse_modality`.
pub(crate) fn decode_modality(m: toothfuse_modality) -> FfiResult<Modality> {
    match m {
        TOOTHFUSE_MODALITY_IOS => Ok(Modality::Ios),
        TOOTHFUSE_MODALITY_CBCT => Ok(Modality::Cbct),
        other => Err(Failure::invalid(format!(
            "modality {other} is neither TOOTHFUSE_MODALITY_IOS (0) nor TOOTHFUSE_MODALITY_CBCT (1)"
        ))),
    }
}

/// Reads a caller's vertex and index buffers into a mesh (finiteness and index range checked).
///
/// # Safety
/// `vertices` must hold `(vertex_count - 1) * stride_bytes + 3 * sizeof(scalar)` readable bytes
/// and `indices` `index_count` readable `uint32_t` (either may be NULL when its count is 0).
unsafe fn read_mesh(
    vertices: *const c_void,
    vertex_count: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
    indices: *const u32,
    index_count: usize,
) -> FfiResult<TriMesh> {
    let scalar = decode_scalar(scalar)?;
    let probe = VertexBuffer {
        bytes: &[],
        count: vertex_count,
        stride: stride_bytes,
        scalar,
    };
    if stride_bytes < 3 * scalar.size() {
        probe.check()?; // names the stride problem
    }
    let len = VertexBuffer::required_len(vertex_count, stride_bytes, scalar).ok_or_else(|| {
        Failure::invalid(format!(
            "{vertex_count} vertices at stride {stride_bytes} bytes overflow the address space"
        ))
    })?;
    // SAFETY: the caller guarantees `len` readable bytes at `vertices` (documented contract).
    let bytes = unsafe { bytes_in(vertices, len, "vertices") }?;
    // SAFETY: the caller guarantees `index_count` readable u32 at `indices`.
    let idx = unsafe { slice_in(indices, index_count, "indices") }?;
    let vb = VertexBuffer {
        bytes,
        count: vertex_count,
        stride: stride_bytes,
        scalar,
    };
    Ok(TriMesh::from_buffers(vb, idx)?)
}

/// Creates an empty session and writes it to `*session_out`.
///
/// Returns TOOTHFUSE_STATUS_NULL_PARAMETER when `session_out` is NULL. Free the session with
/// `toothfuse_session_free`.
///
/// # Safety
/// `session_out` must be NULL or valid for writing one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_new(
    session_out: *mut *mut toothfuse_session,
) -> toothfuse_status {
    ffi_panic_boundary! {
        if let Err(f) = check_out(session_out, "session_out") {
            return f.status;
        }
        let raw = Box::into_raw(Box::new(toothfuse_session::new()));
        // SAFETY: checked non-NULL and aligned; the caller passes a writable pointer slot.
        unsafe { session_out.write(raw) };
        toothfuse_status::Ok
    }
}

/// Frees a session and everything it holds (borrowed views into it become invalid). A no-op
/// on NULL. Calling it twice on the same pointer is undefined behaviour.
///
/// # Safety
/// `session` must be NULL or a session from `toothfuse_session_new` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_free(session: *mut toothfuse_session) {
    ffi_panic_boundary! {
        if !session.is_null() {
            // SAFETY: the caller passes a pointer from Box::into_raw in toothfuse_session_new,
            // not yet freed.
            drop(unsafe { Box::from_raw(session) });
        }
    }
}

/// The detailed message of the last failed call on `session` (naming the tooth, vertex or face
/// at fault), or "" after a successful call. The string belongs to the session: it stays valid
/// until the next call on that session or until it is freed. Never NULL (a NULL `session`
/// gives a static message).
///
/// # Safety
/// `session` must be NULL or a live session.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_last_error(
    session: *const toothfuse_session,
) -> *const c_char {
    ffi_panic_boundary! {
        // SAFETY: the caller guarantees NULL or a live session.
        match unsafe { session.as_ref() } {
            Some(s) => s.last_error.borrow().as_ptr(),
            None => c"session is NULL".as_ptr(),
        }
    }
}

/// Adds one tooth mesh (or replaces the tooth of the same modality and FDI number).
///
/// - `modality`: TOOTHFUSE_MODALITY_IOS (crown, open at its margin, must be 2-manifold) or
///   TOOTHFUSE_MODALITY_CBCT (whole tooth, must be closed and 2-manifold).
/// - `fdi`: FDI tooth number (11-18, 21-28, 31-38, 41-48; primary 51-55 ... 81-85).
/// - `vertices`: `vertex_count` vertices, vertex `i`'s x, y, z (3 packed `scalar` values, in
///   millimetres) at byte offset `i * stride_bytes`; `stride_bytes >= 3 * sizeof(scalar)`; any
///   alignment. Float input is converted exactly to double; double input is kept bit for bit.
/// - `indices`: `index_count` vertex indices, 3 per triangle, counter-clockwise seen from outside.
///
/// The buffers are copied during the call and never kept. Fails with NON_FINITE,
/// INDEX_OUT_OF_BOUNDS, NOT_MANIFOLD (also for degenerate or duplicate triangles, or an open
/// CBCT tooth) or INVALID_ARGUMENT (bad stride, empty mesh, non-FDI number, unknown enum); on
/// any failure the session is unchanged and the message names the tooth and vertex/face.
///
/// # Safety
/// `session` must be NULL or a live session; `vertices` must hold
/// `(vertex_count - 1) * stride_bytes + 3 * sizeof(scalar)` readable bytes and `indices`
/// `index_count` readable `uint32_t` (4-byte aligned).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_add_tooth(
    session: *mut toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    vertices: *const c_void,
    vertex_count: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
    indices: *const u32,
    index_count: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &mut Session| -> FfiResult {
        let modality = decode_modality(modality)?;
        // SAFETY: forwarded contract on the buffers.
        let mesh = unsafe {
            read_mesh(vertices, vertex_count, stride_bytes, scalar, indices, index_count)
        }
        .map_err(|f| Failure::new(f.status, format!("tooth {fdi}: {}", f.message)))?;
        s.add_tooth(modality, fdi, mesh)?;
        Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session_mut(session, body) }
    }
}

/// Adds every tooth of a labeled jaw mesh (all or nothing): the mesh is split by label, label
/// 0 (gingiva) is dropped, every other label must be an FDI number (the message names the
/// first bad label and the vertex or face carrying it), and each tooth is validated as in
/// `toothfuse_session_add_tooth`. Teeth already held with the same FDI number are replaced;
/// other teeth of the modality are kept. On any failure the session is unchanged.
///
/// Vertex and index buffers as in `toothfuse_session_add_tooth`. `labels` holds `label_count`
/// values: one per vertex (`label_count == vertex_count`) for TOOTHFUSE_LABEL_DOMAIN_VERTEX,
/// one per triangle (`label_count == index_count / 3`) for TOOTHFUSE_LABEL_DOMAIN_FACE. Use
/// `toothfuse_session_copy_source_vertices` to map a tooth's vertices back to the jaw.
///
/// # Safety
/// As `toothfuse_session_add_tooth`; `labels` must hold `label_count` readable `int32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_add_jaw(
    session: *mut toothfuse_session,
    modality: toothfuse_modality,
    vertices: *const c_void,
    vertex_count: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
    indices: *const u32,
    index_count: usize,
    labels: *const i32,
    label_count: usize,
    domain: toothfuse_label_domain,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &mut Session| -> FfiResult {
        let modality = decode_modality(modality)?;
        let domain = match domain {
            TOOTHFUSE_LABEL_DOMAIN_VERTEX => LabelDomain::Vertex,
            TOOTHFUSE_LABEL_DOMAIN_FACE => LabelDomain::Face,
            other => {
                return Err(Failure::invalid(format!(
                    "label domain {other} is neither TOOTHFUSE_LABEL_DOMAIN_VERTEX (0) \
                     nor TOOTHFUSE_LABEL_DOMAIN_FACE (1)"
                )));
            }
        };
        // SAFETY: forwarded contract on the buffers.
        let jaw = unsafe {
            read_mesh(vertices, vertex_count, stride_bytes, scalar, indices, index_count)
        }
        .map_err(|f| Failure::new(f.status, format!("jaw mesh: {}", f.message)))?;
        // SAFETY: forwarded contract on `labels`.
        let labels = unsafe { slice_in(labels, label_count, "labels") }?;
        s.add_jaw(modality, &jaw, labels, domain)?;
        Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session_mut(session, body) }
    }
}

/// Switches repair of IOS crowns on entry on or off (off by default; affects later adds only).
///
/// When on, every IOS crown (from `toothfuse_session_add_tooth` or split from a jaw) first goes
/// through the library's open-surface repair: degenerate and duplicate triangles are dropped, an
/// edge keeps at most two triangles, orientation is made consistent, bow-tie vertices are
/// duplicated, islands other than the largest are dropped, and holes whose perimeter is at most
/// `max_hole_fraction` (0 to 1) of the margin's are filled with a centre vertex. Kept vertices keep
/// their exact positions; a filled hole's centre has source vertex UINT32_MAX in
/// `toothfuse_session_copy_source_vertices`. `toothfuse_session_repair_report` says what changed.
/// Real scans need this: most crowns of a decimated, segmented scan are not 2-manifold as given.
///
/// # Safety
/// `session` must be NULL or a live session.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_set_ios_repair(
    session: *mut toothfuse_session,
    enabled: bool,
    max_hole_fraction: f64,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &mut Session| -> FfiResult {
            let opts = enabled.then_some(crate::mesh::RepairOptions { max_hole_fraction });
            s.set_ios_repair(opts)?;
            Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session_mut(session, body) }
    }
}

/// Caps the threads this session's calls use at `max_threads` in all, the calling thread's
/// included (0, the default: no cap; the library then takes as many threads as the CPUs the
/// process may run on allow, at most 4 per step). With 1 every call runs on the calling thread
/// and spawns none: for hosts that run the library inside their own worker threads. The results
/// are the same bit for bit whatever the cap. Other sessions are not affected.
///
/// # Safety
/// `session` must be NULL or a live session.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_set_max_threads(
    session: *mut toothfuse_session,
    max_threads: u32,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contract on `session`.
        unsafe { with_settings(session, |s| s.max_threads.set(max_threads as usize)) }
    }
}

/// Removes tooth `fdi` of `modality`; TOOTHFUSE_STATUS_MISSING_DATA if it is not held.
///
/// # Safety
/// `session` must be NULL or a live session.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_remove_tooth(
    session: *mut toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &mut Session| -> FfiResult {
        s.remove_tooth(decode_modality(modality)?, fdi)?;
        Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session_mut(session, body) }
    }
}

/// Writes the number of teeth held for `modality` to `*count_out`.
///
/// # Safety
/// `session` must be NULL or a live session; `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_tooth_count(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        check_out(count_out, "count_out")?;
        let n = s.teeth(decode_modality(modality)?).len();
        // SAFETY: forwarded contract on `count_out`.
        unsafe { write_out(count_out, n, "count_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the FDI numbers held for `modality`, ascending, into `fdi_out` (room for `capacity`
/// values) and writes how many to `*count_out`. TOOTHFUSE_STATUS_BUFFER_TOO_SMALL (nothing
/// written) when `capacity` is below `toothfuse_session_tooth_count`. `fdi_out` may be NULL
/// when `capacity` is 0.
///
/// # Safety
/// `session` must be NULL or a live session; `fdi_out` must have room for `capacity` `int32_t`;
/// `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_list_teeth(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi_out: *mut i32,
    capacity: usize,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        check_out(count_out, "count_out")?;
        let modality = decode_modality(modality)?;
        let fdis = s.fdis(modality);
        if capacity < fdis.len() {
            return Err(Failure::new(
                toothfuse_status::BufferTooSmall,
                format!(
                    "{} {modality} teeth held but `fdi_out` has room for {capacity}",
                    fdis.len()
                ),
            ));
        }
        // SAFETY: forwarded contract: room for `capacity` >= fdis.len() values.
        let out = unsafe { slice_out(fdi_out, fdis.len(), "fdi_out") }?;
        for (o, f) in out.iter_mut().zip(&fdis) {
            *o = i32::from(*f);
        }
        // SAFETY: forwarded contract on `count_out`.
        unsafe { write_out(count_out, fdis.len(), "count_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CStr;

    fn last_error(s: *const toothfuse_session) -> String {
        // SAFETY: live session; copied at once.
        unsafe { CStr::from_ptr(toothfuse_session_last_error(s)) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn panic_is_caught_and_poisons_the_session() {
        let mut p = std::ptr::null_mut();
        // SAFETY: valid out pointer.
        let st = unsafe { toothfuse_session_new(&mut p) };
        assert_eq!(st, toothfuse_status::Ok);
        let cube: [f64; 12] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.];
        let tris: [u32; 12] = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
        // SAFETY: live session, buffers sized as announced.
        let st = unsafe {
            toothfuse_session_add_tooth(
                p,
                TOOTHFUSE_MODALITY_CBCT,
                31,
                cube.as_ptr().cast(),
                4,
                24,
                super::super::mesh::TOOTHFUSE_SCALAR_FLOAT64,
                tris.as_ptr(),
                12,
            )
        };
        assert_eq!(st, toothfuse_status::Ok, "{}", last_error(p));
        // A body that panics (stands in for a bug in the core).
        // SAFETY: live session.
        let st =
            unsafe { with_session_mut(p, |_| -> FfiResult { panic!("deliberate test panic") }) };
        assert_eq!(st, toothfuse_status::Panic);
        assert_eq!(
            last_error(p),
            "internal error (panic: deliberate test panic); the session is poisoned, free it"
        );
        let mut n = 0usize;
        // SAFETY: live (poisoned) session.
        let st = unsafe { toothfuse_session_tooth_count(p, TOOTHFUSE_MODALITY_CBCT, &mut n) };
        assert_eq!(st, toothfuse_status::Poisoned);
        assert_eq!(n, 0);
        assert!(last_error(p).contains("poisoned"));
        // The outer boundary also catches a panic outside any session.
        let r: toothfuse_status = ffi_panic_boundary! { panic!("outer") };
        assert_eq!(r, toothfuse_status::Panic);
        // SAFETY: created above, freed once.
        unsafe { toothfuse_session_free(p) };
    }
}
