//! The one-call fuse through the C ABI (register + crown cut + stitch) and the fused meshes:
//! sizes, borrowed views, copy-out of positions, triangles, per-vertex source and labels, and
//! the per-tooth quality report. `fdi` 0 selects the whole fused jaw (all fused teeth in one
//! mesh) wherever a fused mesh is asked for.

use super::boundary::{Failure, FfiResult, check_out, copy_out, ffi_panic_boundary, write_out};
use super::mesh::{toothfuse_scalar, write_vertices};
use super::register::{copy_fdis, toothfuse_options, with_options};
use super::session::{toothfuse_session, with_session};
use super::status::toothfuse_status;
use crate::arch::check_fdi;
use crate::session::Session;
use crate::{TriMesh, fuse::FusedTooth};
use std::ffi::c_void;

/// Per-vertex source of a fused mesh vertex (`uint8_t`): the IOS crown.
pub const TOOTHFUSE_SOURCE_IOS: u8 = 0;
/// Per-vertex source: the stitched band (or a filled crown hole).
pub const TOOTHFUSE_SOURCE_BAND: u8 = 1;
/// Per-vertex source: the CBCT root.
pub const TOOTHFUSE_SOURCE_CBCT: u8 = 2;

/// Runs the one-call fuse: registers anew with `options` (NULL = defaults; always, so the
/// transforms and fused meshes agree), then removes each CBCT crown along the registered IOS
/// margin and stitches IOS crown + band + CBCT root into one closed, manifold mesh per tooth
/// (paper section 2.3, Algorithm 1). The results replace earlier ones on the session. A tooth
/// whose fusion fails is listed by `toothfuse_session_skipped` with the reason and the others are
/// delivered. Fails with MISSING_DATA (fewer than three teeth in both modalities, named in the
/// message); on any failure the previous results (registration, fused meshes) are kept.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fuse(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contracts on `session` and `options`.
        unsafe {
            with_options(session, options, |s, o| {
                s.fuse(o)?;
                Ok(())
            })
        }
    }
}

/// Cut and stitch only: removes each CBCT crown along the IOS margin and stitches crown, band and
/// root with the session's last registration (from `toothfuse_session_register`, or an earlier
/// fuse) instead of registering again — for hosts that register once and fuse again with other
/// fusion options (`options`: NULL = defaults; its registration fields and frame are not used,
/// the output frame is the registration's). The same as `toothfuse_session_cut` then
/// `toothfuse_session_stitch` (the cut is kept). WRONG_STATE without a registration (or after
/// the teeth changed); on any failure the previous results are kept.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fuse_registered(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contracts on `session` and `options`.
        unsafe {
            with_options(session, options, |s, o| {
                s.fuse_registered(o)?;
                Ok(())
            })
        }
    }
}

/// Copies the FDI numbers of the fused teeth, ascending, into `fdi_out` (room for `capacity`)
/// and writes how many to `*count_out`; BUFFER_TOO_SMALL (nothing written) when `capacity` is
/// below the count (52 always suffices). WRONG_STATE before a fuse.
///
/// # Safety
/// `session` must be NULL or a live session; `fdi_out` must have room for `capacity` `int32_t`;
/// `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_teeth(
    session: *const toothfuse_session,
    fdi_out: *mut i32,
    capacity: usize,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let fdis: Vec<u8> = s.fused()?.result.jaw.teeth.keys().copied().collect();
            // SAFETY: forwarded contract on the outputs.
            unsafe { copy_fdis(&fdis, fdi_out, capacity, count_out) }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// A fused mesh: the whole jaw (`fdi` 0) or one tooth.
struct FusedMesh<'a> {
    mesh: &'a TriMesh,
    source: &'a [u8],
    labels: Option<&'a [i32]>,
}

/// The fused mesh `fdi` (0 = whole jaw); WRONG_STATE before a fuse, MISSING_DATA for a tooth
/// that was not fused.
fn fused_mesh(s: &Session, fdi: i32) -> FfiResult<FusedMesh<'_>> {
    let jaw = &s.fused()?.result.jaw;
    if fdi == 0 {
        return Ok(FusedMesh {
            mesh: &jaw.mesh,
            source: &jaw.source,
            labels: Some(&jaw.labels),
        });
    }
    let t = fused_tooth(s, fdi)?;
    Ok(FusedMesh {
        mesh: &t.mesh,
        source: &t.source,
        labels: None,
    })
}

fn fused_tooth(s: &Session, fdi: i32) -> FfiResult<&FusedTooth> {
    let key = check_fdi(fdi)?;
    let f = s.fused()?;
    f.result.jaw.teeth.get(&key).ok_or_else(|| {
        let why = s
            .notes()
            .skipped
            .iter()
            .find(|(k, _)| *k == key)
            .map_or("it is not in both modalities".to_string(), |(_, r)| {
                r.to_string_lossy().into_owned()
            });
        Failure::new(
            toothfuse_status::MissingData,
            format!("tooth {fdi} was not fused: {why}"),
        )
    })
}

/// Writes the vertex count and the index count (3 per triangle) of fused mesh `fdi` (0 = whole
/// jaw). WRONG_STATE before a fuse; MISSING_DATA for a tooth that was not fused.
///
/// # Safety
/// `session` must be NULL or a live session; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_size(
    session: *const toothfuse_session,
    fdi: i32,
    vertex_count_out: *mut usize,
    index_count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(vertex_count_out, "vertex_count_out")?;
            check_out(index_count_out, "index_count_out")?;
            let m = fused_mesh(s, fdi)?;
            // SAFETY: forwarded contract on the outputs (checked non-NULL above).
            unsafe {
                write_out(vertex_count_out, m.mesh.positions.len(), "vertex_count_out")?;
                write_out(index_count_out, 3 * m.mesh.triangles.len(), "index_count_out")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// A borrowed, read-only view of a fused mesh. The pointers point into the session: valid
/// until the session's teeth or results change (add, replace, remove, clear, register, fuse,
/// stitch) or it is freed; never free them.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug)]
pub struct toothfuse_fused_view {
    /// `3 * vertex_count` doubles: x, y, z of each vertex, millimetres, output frame.
    pub positions: *const f64,
    /// Number of vertices.
    pub vertex_count: usize,
    /// `index_count` vertex indices, 3 per triangle, counter-clockwise seen from outside.
    pub indices: *const u32,
    /// Number of indices (3 per triangle).
    pub index_count: usize,
    /// `vertex_count` sources: TOOTHFUSE_SOURCE_IOS, _BAND or _CBCT.
    pub source: *const u8,
    /// Whole jaw: `vertex_count` FDI labels; one tooth: NULL (every vertex is that tooth).
    pub labels: *const i32,
}

/// Writes a borrowed view of fused mesh `fdi` (0 = whole jaw) to `*view_out`.
///
/// # Safety
/// `session` must be NULL or a live session; `view_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_view(
    session: *const toothfuse_session,
    fdi: i32,
    view_out: *mut toothfuse_fused_view,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(view_out, "view_out")?;
            let m = fused_mesh(s, fdi)?;
            // DVec3 is #[repr(C)] {x, y, z: f64} and [u32; 3] has no padding: the Vecs are
            // contiguous arrays of doubles / uint32_t.
            let view = toothfuse_fused_view {
                positions: m.mesh.positions.as_ptr().cast::<f64>(),
                vertex_count: m.mesh.positions.len(),
                indices: m.mesh.triangles.as_ptr().cast::<u32>(),
                index_count: 3 * m.mesh.triangles.len(),
                source: m.source.as_ptr(),
                labels: m.labels.map_or(std::ptr::null(), <[i32]>::as_ptr),
            };
            // SAFETY: forwarded contract on `view_out`.
            unsafe { write_out(view_out, view, "view_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the vertices of fused mesh `fdi` (0 = whole jaw) as `toothfuse_session_copy_vertices`
/// does (strided, float or double; BUFFER_TOO_SMALL when `vertex_capacity` is below the count).
///
/// # Safety
/// `session` must be NULL or a live session; `vertices_out` must hold
/// `(vertex_capacity - 1) * stride_bytes + 3 * sizeof(scalar)` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_fused_vertices(
    session: *const toothfuse_session,
    fdi: i32,
    vertices_out: *mut c_void,
    vertex_capacity: usize,
    stride_bytes: usize,
    scalar: toothfuse_scalar,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let m = fused_mesh(s, fdi)?;
            // SAFETY: forwarded contract on `vertices_out`.
            unsafe {
                write_vertices(&m.mesh.positions, vertices_out, vertex_capacity, stride_bytes, scalar)
            }
            .map_err(|f| Failure::new(f.status, format!("fused mesh {fdi}: {}", f.message)))
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the triangle indices of fused mesh `fdi` (0 = whole jaw), 3 per triangle;
/// BUFFER_TOO_SMALL (nothing written) when `index_capacity` is below the index count.
///
/// # Safety
/// `session` must be NULL or a live session; `indices_out` room for `index_capacity` `uint32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_fused_indices(
    session: *const toothfuse_session,
    fdi: i32,
    indices_out: *mut u32,
    index_capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let m = fused_mesh(s, fdi)?;
            let subject = format!("fused mesh {fdi}");
            let tris = m.mesh.triangles.as_flattened();
            // SAFETY: forwarded contract on `indices_out`.
            unsafe { copy_out(tris, indices_out, index_capacity, "indices_out", &subject, "indices") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the per-vertex source (TOOTHFUSE_SOURCE_*) of fused mesh `fdi` (0 = whole jaw);
/// BUFFER_TOO_SMALL (nothing written) when `capacity` is below the vertex count.
///
/// # Safety
/// `session` must be NULL or a live session; `source_out` room for `capacity` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_fused_sources(
    session: *const toothfuse_session,
    fdi: i32,
    source_out: *mut u8,
    capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let m = fused_mesh(s, fdi)?;
            let subject = format!("fused mesh {fdi}");
            // SAFETY: forwarded contract on `source_out`.
            unsafe { copy_out(m.source, source_out, capacity, "source_out", &subject, "sources") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the per-vertex FDI labels of the whole fused jaw (vertex count from
/// `toothfuse_session_fused_size(session, 0, ...)`); BUFFER_TOO_SMALL (nothing written) when
/// `capacity` is below it. WRONG_STATE before a fuse.
///
/// # Safety
/// `session` must be NULL or a live session; `labels_out` room for `capacity` `int32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_copy_fused_labels(
    session: *const toothfuse_session,
    labels_out: *mut i32,
    capacity: usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let labels = &s.fused()?.result.jaw.labels;
            // SAFETY: forwarded contract on `labels_out`.
            unsafe { copy_out(labels, labels_out, capacity, "labels_out", "fused mesh 0", "labels") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Quality of one fused tooth, as measured by toothfuse itself (the C++ tests check the same
/// facts with VTK and OpenMesh).
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct toothfuse_fused_quality {
    /// Enclosed volume (mm^3), positive when outward oriented.
    pub volume: f64,
    /// Smallest angle (degrees) of any band triangle.
    pub band_min_angle_deg: f64,
    /// Mean band edge length (mm).
    pub band_edge_mean: f64,
    /// Connected components (1 for a good fusion).
    pub components: usize,
    /// Edges used by one face (0 when closed).
    pub boundary_edges: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Vertices joining separate fans of faces.
    pub non_manifold_vertices: usize,
    /// Intersecting face pairs; SIZE_MAX when the check was not run.
    pub self_intersections: usize,
    /// Degenerate faces.
    pub degenerate_faces: usize,
    /// Band triangles.
    pub band_faces: usize,
    /// IOS crown vertices kept: all of them except the ones trimmed from the margin fringe
    /// (see `toothfuse_session_fused_trim`) and the ones the crown repair dropped (see
    /// `toothfuse_session_fused_dropped`).
    pub crown_vertices: usize,
    /// Every edge in exactly two faces.
    pub closed: bool,
    /// No non-manifold edge or vertex.
    pub manifold: bool,
    /// Closed, manifold, one component, positive volume, nothing degenerate or intersecting.
    pub watertight: bool,
}

/// Writes the quality report of fused tooth `fdi` to `*quality_out`. WRONG_STATE before a fuse;
/// MISSING_DATA (with the reason) for a tooth that was not fused.
///
/// # Safety
/// `session` must be NULL or a live session; `quality_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_quality(
    session: *const toothfuse_session,
    fdi: i32,
    quality_out: *mut toothfuse_fused_quality,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(quality_out, "quality_out")?;
            let q = &fused_tooth(s, fdi)?.quality;
            let out = toothfuse_fused_quality {
                volume: q.volume,
                band_min_angle_deg: q.band_min_angle_deg,
                band_edge_mean: q.band_edge_mean,
                components: q.components,
                boundary_edges: q.boundary_edges,
                non_manifold_edges: q.non_manifold_edges,
                non_manifold_vertices: q.non_manifold_vertices,
                self_intersections: q.self_intersections.unwrap_or(usize::MAX),
                degenerate_faces: q.degenerate_faces,
                band_faces: q.band_faces,
                crown_vertices: q.crown_vertices,
                closed: q.closed,
                manifold: q.manifold,
                watertight: q.watertight(),
            };
            // SAFETY: forwarded contract on `quality_out`.
            unsafe { write_out(quality_out, out, "quality_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes the intersecting face pairs of fused tooth `fdi` by origin: to `*band_out` the pairs
/// the fusion added and could not remove, those with a band face and those with a face added to
/// the crown (a hole's cap, a slit's strip) (0 when the output contract's "no crossing added"
/// holds for this tooth), to `*ios_out` the pairs of two kept IOS crown faces (the input crown's
/// own crossings, kept as given). Both exact; the first is counted during the fusion,
/// the second on this call (an all-pairs check of the crown: ~10–20 ms for 15 000 faces).
/// WRONG_STATE before a fuse; MISSING_DATA (with the reason) for a tooth that was not fused.
///
/// # Safety
/// `session` must be NULL or a live session; `band_out` and `ios_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_crossings(
    session: *const toothfuse_session,
    fdi: i32,
    band_out: *mut usize,
    ios_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(band_out, "band_out")?;
            check_out(ios_out, "ios_out")?;
            let t = fused_tooth(s, fdi)?;
            // SAFETY: forwarded contract on both output pointers.
            unsafe {
                write_out(band_out, t.quality.crossings_added(), "band_out")?;
                write_out(ios_out, t.ios_self_intersections(), "ios_out")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes how much of fused tooth `fdi`'s IOS crown was trimmed from its margin fringe: the
/// number of IOS crown vertices dropped (folded over other crown faces, or crossed by the band)
/// to `*vertices_out` and the largest geodesic distance (mm) of a dropped vertex from the original
/// margin to `*reach_mm_out` (0 when none was dropped; at most the fringe reach, 0.3 mm by
/// default, or 3x that on a tooth the band could not clear within it, whose warning says so).
/// Every other IOS crown vertex is in the fused mesh bitwise. WRONG_STATE before a fuse;
/// MISSING_DATA (with the reason) for a tooth that was not fused.
///
/// # Safety
/// `session` must be NULL or a live session; `vertices_out` and `reach_mm_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_trim(
    session: *const toothfuse_session,
    fdi: i32,
    vertices_out: *mut usize,
    reach_mm_out: *mut f64,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(vertices_out, "vertices_out")?;
            check_out(reach_mm_out, "reach_mm_out")?;
            let q = &fused_tooth(s, fdi)?.quality;
            // SAFETY: forwarded contract on both output pointers.
            unsafe {
                write_out(vertices_out, q.ios_vertices_trimmed, "vertices_out")?;
                write_out(reach_mm_out, q.ios_trim_reach_mm, "reach_mm_out")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes to `*vertices_out` the number of fused tooth `fdi`'s IOS crown vertices that the crown
/// repair dropped: stray tooth-labelled islands apart from the crown (a segmentation tool's
/// label noise, given back to the gingiva) and vertices in no face; 0 on a clean crown. With the
/// trimmed ones (`toothfuse_session_fused_trim`) these are all the crown's input vertices missing
/// from the fused mesh. WRONG_STATE before a fuse; MISSING_DATA (with the reason) for a tooth that
/// was not fused.
///
/// # Safety
/// `session` must be NULL or a live session; `vertices_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_fused_dropped(
    session: *const toothfuse_session,
    fdi: i32,
    vertices_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(vertices_out, "vertices_out")?;
            let q = &fused_tooth(s, fdi)?.quality;
            // SAFETY: forwarded contract on `vertices_out`.
            unsafe { write_out(vertices_out, q.ios_vertices_dropped, "vertices_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}
