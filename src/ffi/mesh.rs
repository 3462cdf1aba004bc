//! Reading a held tooth mesh back: sizes, a borrowed view, copy-out (double or float, strided),
//! the map to the caller's input vertices, and topology facts.

use super::boundary::{
    Failure, FfiResult, check_out, copy_out, ffi_panic_boundary, slice_out, write_out,
};
use super::session::{decode_modality, toothfuse_modality, toothfuse_session, with_session};
use super::status::toothfuse_status;
use crate::mesh::{Scalar, VertexBuffer};
use crate::session::{Modality, Session, Tooth};
use std::ffi::c_void;

/// Scalar type of a vertex buffer: one of the `TOOTHFUSE_SCALAR_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_scalar = u32;
/// 32-bit IEEE `float`.
pub const TOOTHFUSE_SCALAR_FLOAT32: toothfuse_scalar = 0;
/// 64-bit IEEE `double`.
pub const TOOTHFUSE_SCALAR_FLOAT64: toothfuse_scalar = 1;

/// Decodes a `toothfuse_scalar`.
pub(crate) fn decode_scalar(s: toothfuse_scalar) -> FfiResult<Scalar> {
    match s {
        TOOTHFUSE_SCALAR_FLOAT32 => Ok(Scalar::F32),
        TOOTHFUSE_SCALAR_FLOAT64 => Ok(Scalar::F64),
        other => Err(Failure::invalid(format!(
            "scalar type {other} is neither TOOTHFUSE_SCALAR_FLOAT32 (0) nor TOOTHFUSE_SCALAR_FLOAT64 (1)"
        ))),
    }
}

/// A borrowed, read-only view of a held mesh. The pointers point into the session: they stay
/// valid until the session is changed (any add, replace, remove or clear call) or freed; never
/// free them.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug)]
pub struct toothfuse_mesh_view {
    /// `3 * vertex_count` doubles: x, y, z of each vertex, in millimetres.
    pub positions: *const f64,
    /// Number of vertices.
    pub vertex_count: usize,
    /// `index_count` vertex indices, 3 per triangle, counter-clockwise seen from outside.
    pub indices: *const u32,
    /// Number of indices (3 per triangle).
    pub index_count: usize,
}

/// Topological facts about a held mesh.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct toothfuse_mesh_info {
    /// Number of vertices.
    pub vertex_count: usize,
    /// Number of triangles.
    pub triangle_count: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Closed boundary loops (an IOS crown has one: its gingival margin; a CBCT tooth none).
    pub boundary_loops: usize,
    /// Vertices in the longest boundary loop (0 when closed).
    pub longest_loop_vertices: usize,
    /// Connected components (by shared edges).
    pub components: usize,
    /// Every edge is used by exactly two triangles.
    pub closed: bool,
    /// No non-manifold edge or vertex.
    pub manifold: bool,
    /// Signed enclosed volume in mm^3 (positive for a closed outward-oriented surface; only
    /// meaningful when closed).
    pub signed_volume: f64,
    /// Surface area in mm^2.
    pub area: f64,
}

/// What IOS repair changed in one tooth (see `toothfuse_session_set_ios_repair`).
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct toothfuse_repair_report {
    /// The tooth went through repair (IOS with repair on when it was added); all counts are 0
    /// otherwise.
    pub repaired: bool,
    /// Triangles dropped for repeating a vertex or having zero area.
    pub degenerate_faces: usize,
    /// Triangles dropped as duplicates of an earlier triangle.
    pub duplicate_faces: usize,
    /// Triangles dropped because their edge already had two triangles.
    pub non_manifold_faces: usize,
    /// Triangles flipped to agree with their neighbours.
    pub flipped_faces: usize,
    /// Triangles dropped with components other than the largest.
    pub island_faces: usize,
    /// Vertices duplicated to split bow-ties.
    pub split_vertices: usize,
    /// Holes filled (boundary loops other than the margin).
    pub filled_holes: usize,
    /// Vertices added as hole centres (source vertex UINT32_MAX).
    pub added_vertices: usize,
    /// Triangles taken with a hole they lay over (no cap tried could clear them; their
    /// vertices stay unless only they used them).
    pub rim_faces_removed: usize,
    /// Filled holes whose cap still crosses the surface (0 unless no cap tried, with faces
    /// taken, was clear).
    pub crossing_caps: usize,
}

/// Writes `positions` into a caller's strided vertex buffer (x, y, z as 3 packed `scalar` values
/// at byte offset `i * stride_bytes`); BUFFER_TOO_SMALL when `vertex_capacity` is below the count.
///
/// # Safety
/// `vertices_out` must hold `(vertex_capacity - 1) * stride_bytes + 3 * sizeof(scalar)` writable
/// bytes.
pub(crate) unsafe fn write_vertices(
    positions: &[glam::DVec3],
    vertices_out: *mut c_void,
    vertex_capacity: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
) -> FfiResult {
    let scalar = decode_scalar(scalar)?;
    let size = scalar.size();
    if stride_bytes < 3 * size {
        return Err(Failure::invalid(format!(
            "vertex stride {stride_bytes} bytes is smaller than one vertex ({} bytes)",
            3 * size
        )));
    }
    let n = positions.len();
    if vertex_capacity < n {
        return Err(Failure::new(
            toothfuse_status::BufferTooSmall,
            format!("{n} vertices to copy but the buffer has room for {vertex_capacity}"),
        ));
    }
    let len = VertexBuffer::required_len(n, stride_bytes, scalar).ok_or_else(|| {
        Failure::invalid(format!(
            "{n} vertices at stride {stride_bytes} bytes overflow the address space"
        ))
    })?;
    // SAFETY: the caller guarantees room for `vertex_capacity >= n` vertices at this stride,
    // i.e. at least `len` writable bytes.
    let out = unsafe { slice_out(vertices_out.cast::<u8>(), len, "vertices_out") }?;
    for (i, p) in positions.iter().enumerate() {
        let base = i * stride_bytes;
        for (k, c) in p.to_array().into_iter().enumerate() {
            let o = base + k * size;
            match scalar {
                Scalar::F32 => out[o..o + 4].copy_from_slice(&(c as f32).to_ne_bytes()),
                Scalar::F64 => out[o..o + 8].copy_from_slice(&c.to_ne_bytes()),
            }
        }
    }
    Ok(())
}

/// Finds the tooth, naming it on failure.
fn find(s: &Session, modality: toothfuse_modality, fdi: i32) -> FfiResult<&Tooth> {
    let m: Modality = decode_modality(modality)?;
    Ok(s.tooth(m, fdi)?)
}

/// Writes the vertex count and the index count (3 per triangle) of tooth `fdi` of `modality`.
///
/// # Safety
/// `session` must be NULL or a live session; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_mesh_size(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    vertex_count_out: *mut usize,
    index_count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        check_out(vertex_count_out, "vertex_count_out")?;
        check_out(index_count_out, "index_count_out")?;
        let t = find(s, modality, fdi)?;
        // SAFETY: forwarded contract on the outputs (checked non-NULL above).
        unsafe {
            write_out(vertex_count_out, t.mesh.positions.len(), "vertex_count_out")?;
            write_out(index_count_out, 3 * t.mesh.triangles.len(), "index_count_out")
        }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes a borrowed view of tooth `fdi` of `modality` to `*view_out` (see
/// `toothfuse_mesh_view` for how long it stays valid).
///
/// # Safety
/// `session` must be NULL or a live session; `view_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_mesh_view(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    view_out: *mut toothfuse_mesh_view,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        check_out(view_out, "view_out")?;
        let t = find(s, modality, fdi)?;
        // glam's DVec3 is #[repr(C)] { x, y, z: f64 } and [u32; 3] has no padding, so
        // the Vecs are contiguous arrays of doubles / uint32_t.
        let view = toothfuse_mesh_view {
            positions: t.mesh.positions.as_ptr().cast::<f64>(),
            vertex_count: t.mesh.positions.len(),
            indices: t.mesh.triangles.as_ptr().cast::<u32>(),
            index_count: 3 * t.mesh.triangles.len(),
        };
        // SAFETY: forwarded contract on `view_out`.
        unsafe { write_out(view_out, view, "view_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the vertices of tooth `fdi` of `modality` into caller memory: vertex `i`'s x, y, z as
/// 3 packed `scalar` values at byte offset `i * stride_bytes` of `vertices_out` (bytes between
/// vertices are left untouched; any alignment). Double output is bit-identical to what the
/// session holds; float output is rounded to nearest. TOOTHFUSE_STATUS_BUFFER_TOO_SMALL
/// (nothing written) when `vertex_capacity` is below the vertex count from
/// `toothfuse_session_mesh_size`.
///
/// # Safety
/// `session` must be NULL or a live session; `vertices_out` must hold
/// `(vertex_capacity - 1) * stride_bytes + 3 * sizeof(scalar)` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_vertices(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    vertices_out: *mut c_void,
    vertex_capacity: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        let t = find(s, modality, fdi)?;
        // SAFETY: forwarded contract on `vertices_out`.
        unsafe {
            write_vertices(&t.mesh.positions, vertices_out, vertex_capacity, stride_bytes, scalar)
        }
        .map_err(|f| Failure::new(f.status, format!("tooth {fdi}: {}", f.message)))
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the triangle indices of tooth `fdi` of `modality` (3 per triangle) into
/// `indices_out`. TOOTHFUSE_STATUS_BUFFER_TOO_SMALL (nothing written) when `index_capacity` is
/// below the index count from `toothfuse_session_mesh_size`.
///
/// # Safety
/// `session` must be NULL or a live session; `indices_out` must have room for
/// `index_capacity` `uint32_t` (4-byte aligned).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_indices(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    indices_out: *mut u32,
    index_capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        let t = find(s, modality, fdi)?;
        let tris = t.mesh.triangles.as_flattened();
        let subject = format!("tooth {fdi}");
        // SAFETY: forwarded contract on `indices_out`.
        unsafe { copy_out(tris, indices_out, index_capacity, "indices_out", &subject, "indices") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies, for each vertex of tooth `fdi` of `modality`, the index of the vertex it came from
/// in the buffer the caller passed (the jaw mesh for `toothfuse_session_add_jaw`, the identity
/// for `toothfuse_session_add_tooth`; UINT32_MAX for a vertex IOS repair added). Room for the vertex count is needed, else
/// TOOTHFUSE_STATUS_BUFFER_TOO_SMALL (nothing written).
///
/// # Safety
/// `session` must be NULL or a live session; `source_out` must have room for `capacity`
/// `uint32_t` (4-byte aligned).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_source_vertices(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    source_out: *mut u32,
    capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        let t = find(s, modality, fdi)?;
        let subject = format!("tooth {fdi}");
        let ids = &t.source_vertex;
        // SAFETY: forwarded contract on `source_out`.
        unsafe { copy_out(ids, source_out, capacity, "source_out", &subject, "source vertex ids") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes what IOS repair changed in tooth `fdi` of `modality` to `*report_out` (all zero, with
/// `repaired` false, for a tooth added without repair).
///
/// # Safety
/// `session` must be NULL or a live session; `report_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_repair_report(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    report_out: *mut toothfuse_repair_report,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(report_out, "report_out")?;
            let t = find(s, modality, fdi)?;
            let r = match &t.repair {
                None => toothfuse_repair_report::default(),
                Some(r) => toothfuse_repair_report {
                    repaired: true,
                    degenerate_faces: r.degenerate_faces,
                    duplicate_faces: r.duplicate_faces,
                    non_manifold_faces: r.non_manifold_faces,
                    flipped_faces: r.flipped_faces,
                    island_faces: r.island_faces,
                    split_vertices: r.split_vertices,
                    filled_holes: r.filled_holes,
                    added_vertices: r.added_vertices,
                    rim_faces_removed: r.rim_faces_removed,
                    crossing_caps: r.crossing_caps,
                },
            };
            // SAFETY: forwarded contract on `report_out`.
            unsafe { write_out(report_out, r, "report_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes topology facts (boundary loops, closed, manifold, components, volume, area) about
/// tooth `fdi` of `modality` to `*info_out`.
///
/// # Safety
/// `session` must be NULL or a live session; `info_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_mesh_info(
    session: *const toothfuse_session,
    modality: toothfuse_modality,
    fdi: i32,
    info_out: *mut toothfuse_mesh_info,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
        check_out(info_out, "info_out")?;
        let t = find(s, modality, fdi)?;
        let r = &t.report;
        let loops = crate::mesh::boundary_loops(&t.mesh);
        let info = toothfuse_mesh_info {
            vertex_count: r.vertices,
            triangle_count: r.faces,
            boundary_edges: r.boundary_edges,
            boundary_loops: loops.len(),
            longest_loop_vertices: loops.first().map_or(0, Vec::len),
            components: r.components,
            closed: r.boundary_edges == 0 && r.non_manifold_edges == 0,
            manifold: r.non_manifold_edges == 0 && r.non_manifold_vertices == 0,
            signed_volume: t.mesh.signed_volume(),
            area: t.mesh.area(),
        };
        // SAFETY: forwarded contract on `info_out`.
        unsafe { write_out(info_out, info, "info_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}
