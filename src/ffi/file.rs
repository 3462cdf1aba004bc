//! Reading mesh files (PLY, STL, OBJ + Teeth3DS JSON, VTP, legacy VTK) through the C ABI: a
//! `toothfuse_mesh_file` handle holding the geometry and the labels converted to FDI, with the
//! label array and numbering used, so bindings need no file reader of their own.

use super::boundary::{Failure, FfiResult, check_out, ffi_panic_boundary};
use super::mesh::toothfuse_mesh_view;
use super::session::{
    TOOTHFUSE_LABEL_DOMAIN_FACE, TOOTHFUSE_LABEL_DOMAIN_VERTEX, toothfuse_label_domain,
    toothfuse_session, with_session,
};
use super::status::toothfuse_status;
use crate::io::{Detected, LabelScheme, detect_scheme, labels_to_fdi, read_mesh_with};
use crate::mesh::LabeledMesh;
use serde_json::json;
use std::ffi::{CStr, CString, c_char};

/// Tooth numbering of a file's labels: one of the `TOOTHFUSE_NUMBERING_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_numbering = u32;
/// Detect the numbering from the array name or the values (refused when ambiguous).
pub const TOOTHFUSE_NUMBERING_AUTO: toothfuse_numbering = 0;
/// FDI two-digit numbers.
pub const TOOTHFUSE_NUMBERING_FDI: toothfuse_numbering = 1;
/// Universal 1-32 (33: gingiva, as the DCBIA tools write it).
pub const TOOTHFUSE_NUMBERING_UNIVERSAL: toothfuse_numbering = 2;
/// Mesh Labeler / MeshSegNet ordinals.
pub const TOOTHFUSE_NUMBERING_MESHLABELER: toothfuse_numbering = 3;

/// A mesh read from a file: geometry, labels converted to FDI (0 = gingiva), and a JSON
/// description of how the labels were read. Opaque; free with `toothfuse_mesh_file_free`.
/// Not thread-safe for concurrent use; may be moved between threads.
#[allow(non_camel_case_types)]
pub struct toothfuse_mesh_file {
    mesh: LabeledMesh,
    positions: Vec<f64>,
    indices: Vec<u32>,
    description: CString,
}

fn decode_numbering(n: toothfuse_numbering) -> FfiResult<Option<LabelScheme>> {
    match n {
        TOOTHFUSE_NUMBERING_AUTO => Ok(None),
        TOOTHFUSE_NUMBERING_FDI => Ok(Some(LabelScheme::Fdi)),
        TOOTHFUSE_NUMBERING_UNIVERSAL => Ok(Some(LabelScheme::Universal)),
        TOOTHFUSE_NUMBERING_MESHLABELER => Ok(Some(LabelScheme::MeshLabeler)),
        other => Err(Failure::invalid(format!(
            "numbering {other} is not a TOOTHFUSE_NUMBERING_* value (0-3)"
        ))),
    }
}

/// A NUL-terminated UTF-8 parameter (`None` for NULL when `optional`).
///
/// # Safety
/// `p` must be NULL or a NUL-terminated string.
unsafe fn c_str<'a>(p: *const c_char, name: &str, optional: bool) -> FfiResult<Option<&'a str>> {
    if p.is_null() {
        return if optional {
            Ok(None)
        } else {
            Err(Failure::null(name))
        };
    }
    // SAFETY: non-NULL and NUL-terminated by the caller's contract.
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str()
        .map(Some)
        .map_err(|_| Failure::invalid(format!("parameter `{name}` is not UTF-8")))
}

/// Reads the file and converts its labels; the handle's content.
fn read(
    path: &str,
    array: Option<&str>,
    numbering: Option<LabelScheme>,
) -> FfiResult<toothfuse_mesh_file> {
    let f = read_mesh_with(path, array)?;
    let mut mesh = f.mesh;
    let labels = mesh.face_labels.as_ref().or(mesh.vertex_labels.as_ref());
    let detected: Option<Detected> = match (numbering, labels) {
        (_, None) => None,
        (Some(s), Some(_)) => Some(Detected {
            scheme: s,
            reason: "given".into(),
        }),
        (None, Some(l)) => Some(detect_scheme(
            path,
            f.label_array.as_deref(),
            f.teeth3ds_json,
            l,
        )?),
    };
    if let Some(d) = &detected {
        for l in [&mut mesh.vertex_labels, &mut mesh.face_labels]
            .into_iter()
            .flatten()
        {
            labels_to_fdi(d.scheme, l).map_err(|e| Failure::invalid(format!("{path}: {e}")))?;
        }
    }
    let arrays: Vec<serde_json::Value> = f
        .arrays
        .iter()
        .map(|a| json!({"name": a.name, "on_points": a.on_points, "type": a.data_type}))
        .collect();
    let description = json!({
        "label_array": f.label_array,
        "numbering": detected.as_ref().map(|d| d.scheme.name()),
        "numbering_reason": detected.as_ref().map(|d| d.reason.clone()),
        "arrays": arrays,
    })
    .to_string();
    let positions = mesh
        .mesh
        .positions
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    let indices = mesh.mesh.triangles.iter().flatten().copied().collect();
    Ok(toothfuse_mesh_file {
        mesh,
        positions,
        indices,
        description: CString::new(description).unwrap_or_default(),
    })
}

/// Reads a mesh file (`.ply`, `.stl`, `.obj` with a Teeth3DS `.json` beside it, `.vtp`, `.vtk`;
/// by extension) into a new handle written to `*file_out` (only on success).
///
/// - `path`: NUL-terminated UTF-8 file path.
/// - `label_array`: the name of the label array (point or cell data; PLY vertex or face
///   property), or NULL to choose by name (`label`, `labels`, `UniversalID`, `PredictedID`,
///   `FDI`, ...). A name the file does not hold fails with MISSING_DATA listing its arrays.
/// - `numbering`: a `TOOTHFUSE_NUMBERING_*` value; AUTO detects it from the array name or the
///   values and fails with INVALID_ARGUMENT when they are valid in two numberings.
///
/// The labels come back as FDI numbers (0 = gingiva). Failures (unreadable or malformed file,
/// named array absent, labels not in the numbering) return the status and leave the message on
/// `session` (`toothfuse_session_last_error`); the session's teeth are not touched.
///
/// # Safety
/// `session` must be NULL or a live session; `path` (and `label_array` when not NULL) must be
/// NUL-terminated strings; `file_out` must be NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_read_file(
    session: *const toothfuse_session,
    path: *const c_char,
    label_array: *const c_char,
    numbering: toothfuse_numbering,
    file_out: *mut *mut toothfuse_mesh_file,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: the caller guarantees NULL or a live session; the strings are NUL-terminated.
        unsafe {
            with_session(session, |_| {
                check_out(file_out, "file_out")?;
                let path = c_str(path, "path", false)?.unwrap_or_default();
                let array = c_str(label_array, "label_array", true)?;
                let numbering = decode_numbering(numbering)?;
                let file = read(path, array, numbering)?;
                file_out.write(Box::into_raw(Box::new(file)));
                Ok(())
            })
        }
    }
}

/// Frees a file handle (a no-op on NULL); views into it become invalid.
///
/// # Safety
/// `file` must be NULL or a handle from `toothfuse_session_read_file` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_mesh_file_free(file: *mut toothfuse_mesh_file) {
    ffi_panic_boundary! {
        if !file.is_null() {
            // SAFETY: a pointer from Box::into_raw in toothfuse_session_read_file, not yet freed.
            drop(unsafe { Box::from_raw(file) });
        }
    }
}

/// A borrowed view of the file's geometry (double x, y, z per vertex; 3 indices per triangle,
/// polygons fan-triangulated), valid until the handle is freed.
///
/// # Safety
/// `file` must be NULL or a live handle; `view_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_mesh_file_view(
    file: *const toothfuse_mesh_file,
    view_out: *mut toothfuse_mesh_view,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: the caller guarantees NULL or a live handle.
        let Some(f) = (unsafe { file.as_ref() }) else {
            return toothfuse_status::NullParameter;
        };
        if let Err(e) = check_out(view_out, "view_out") {
            return e.status;
        }
        let view = toothfuse_mesh_view {
            positions: f.positions.as_ptr(),
            vertex_count: f.mesh.mesh.positions.len(),
            indices: f.indices.as_ptr(),
            index_count: f.indices.len(),
        };
        // SAFETY: checked non-NULL and aligned above; writable by the caller's contract.
        unsafe { view_out.write(view) };
        toothfuse_status::Ok
    }
}

/// The file's labels as FDI numbers (0 = gingiva) in `domain` (TOOTHFUSE_LABEL_DOMAIN_VERTEX:
/// one per vertex; _FACE: one per triangle), borrowed until the handle is freed. A file without
/// labels in that domain gives `*labels_out = NULL`, `*count_out = 0` and OK.
///
/// # Safety
/// `file` must be NULL or a live handle; the out pointers NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_mesh_file_labels(
    file: *const toothfuse_mesh_file,
    domain: toothfuse_label_domain,
    labels_out: *mut *const i32,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: the caller guarantees NULL or a live handle.
        let Some(f) = (unsafe { file.as_ref() }) else {
            return toothfuse_status::NullParameter;
        };
        let labels = match domain {
            TOOTHFUSE_LABEL_DOMAIN_VERTEX => &f.mesh.vertex_labels,
            TOOTHFUSE_LABEL_DOMAIN_FACE => &f.mesh.face_labels,
            _ => return toothfuse_status::InvalidArgument,
        };
        for e in [check_out(labels_out, "labels_out"), check_out(count_out, "count_out")] {
            if let Err(e) = e {
                return e.status;
            }
        }
        let (p, n) = labels
            .as_ref()
            .map_or((std::ptr::null(), 0), |l| (l.as_ptr(), l.len()));
        // SAFETY: both checked non-NULL and aligned above; writable by the caller's contract.
        unsafe {
            labels_out.write(p);
            count_out.write(n);
        }
        toothfuse_status::Ok
    }
}

/// How the file's labels were read, as a NUL-terminated JSON object:
/// `{"label_array": name or null, "numbering": "fdi"|"universal"|"meshlabeler" or null,
/// "numbering_reason": text or null, "arrays": [{"name", "on_points", "type"}, ...]}`.
/// Borrowed until the handle is freed; NULL for a NULL handle.
///
/// # Safety
/// `file` must be NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_mesh_file_description(
    file: *const toothfuse_mesh_file,
) -> *const c_char {
    ffi_panic_boundary! {
        // SAFETY: the caller guarantees NULL or a live handle.
        match unsafe { file.as_ref() } {
            Some(f) => f.description.as_ptr(),
            None => std::ptr::null(),
        }
    }
}
