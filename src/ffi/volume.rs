//! Adding the CBCT teeth of a label volume (one label per tooth, or one per jaw split with the
//! IOS teeth held) to a session.

use super::boundary::{Failure, FfiResult, ffi_panic_boundary, slice_in, write_out};
use super::session::{toothfuse_session, with_session_mut};
use super::status::toothfuse_status;
use crate::session::Session;
use crate::volume::{Frame, LabelVolume, SurfaceOptions, VolumeScheme};
use glam::DMat4;
use std::ffi::c_void;

/// Element type of a label buffer: one of the `TOOTHFUSE_LABEL_TYPE_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_label_type = u32;
/// `uint8_t` labels.
pub const TOOTHFUSE_LABEL_TYPE_UINT8: toothfuse_label_type = 0;
/// `uint16_t` labels (2-byte aligned).
pub const TOOTHFUSE_LABEL_TYPE_UINT16: toothfuse_label_type = 1;
/// `int16_t` labels (2-byte aligned); negative values are refused.
pub const TOOTHFUSE_LABEL_TYPE_INT16: toothfuse_label_type = 2;
/// `int32_t` labels (4-byte aligned); values outside 0-65535 are refused.
pub const TOOTHFUSE_LABEL_TYPE_INT32: toothfuse_label_type = 3;

/// Numbering of a label volume's values: one of the `TOOTHFUSE_VOLUME_SCHEME_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_volume_scheme = u32;
/// One label per tooth, the FDI number (STS 2024, most tooth segmentation models).
pub const TOOTHFUSE_VOLUME_SCHEME_FDI: toothfuse_volume_scheme = 0;
/// One label per tooth, Universal numbering 1-32.
pub const TOOTHFUSE_VOLUME_SCHEME_UNIVERSAL: toothfuse_volume_scheme = 1;
/// ToothFairy2: teeth at their FDI numbers; other structures (bones, canals, sinuses, pulps,
/// implants) are skipped.
pub const TOOTHFUSE_VOLUME_SCHEME_TOOTHFAIRY2: toothfuse_volume_scheme = 2;
/// DentalSegmentator: one label per jaw (3 upper teeth, 4 lower teeth; 1, 2, 5 bones and canal
/// ignored), split into teeth with the IOS teeth already added to the session.
pub const TOOTHFUSE_VOLUME_SCHEME_DENTALSEGMENTATOR: toothfuse_volume_scheme = 3;

/// Copies a caller's label buffer into u16 labels, refusing values outside 0-65535.
///
/// # Safety
/// `labels` must hold `count` readable values of the type `label_type` names, aligned for it.
unsafe fn read_labels(
    labels: *const c_void,
    count: usize,
    label_type: toothfuse_label_type,
) -> FfiResult<Vec<u16>> {
    fn convert<T: Copy + Into<i64>>(s: &[T]) -> FfiResult<Vec<u16>> {
        s.iter()
            .enumerate()
            .map(|(i, &v)| {
                let v: i64 = v.into();
                u16::try_from(v).map_err(|_| {
                    Failure::invalid(format!(
                        "label {v} at voxel {i} is outside 0-65535: a label volume holds \
                         non-negative integer labels (an intensity image is not one)"
                    ))
                })
            })
            .collect()
    }
    match label_type {
        TOOTHFUSE_LABEL_TYPE_UINT8 => {
            // SAFETY: the caller guarantees `count` readable u8 at `labels`.
            convert(unsafe { slice_in(labels.cast::<u8>(), count, "labels") }?)
        }
        TOOTHFUSE_LABEL_TYPE_UINT16 => {
            // SAFETY: the caller guarantees `count` readable, aligned u16 at `labels`.
            Ok(unsafe { slice_in(labels.cast::<u16>(), count, "labels") }?.to_vec())
        }
        TOOTHFUSE_LABEL_TYPE_INT16 => {
            // SAFETY: the caller guarantees `count` readable, aligned i16 at `labels`.
            convert(unsafe { slice_in(labels.cast::<i16>(), count, "labels") }?)
        }
        TOOTHFUSE_LABEL_TYPE_INT32 => {
            // SAFETY: the caller guarantees `count` readable, aligned i32 at `labels`.
            convert(unsafe { slice_in(labels.cast::<i32>(), count, "labels") }?)
        }
        other => Err(Failure::invalid(format!(
            "label type {other} is not one of TOOTHFUSE_LABEL_TYPE_UINT8 (0), UINT16 (1), \
             INT16 (2), INT32 (3)"
        ))),
    }
}

fn decode_volume_scheme(s: toothfuse_volume_scheme) -> FfiResult<VolumeScheme> {
    match s {
        TOOTHFUSE_VOLUME_SCHEME_FDI => Ok(VolumeScheme::Fdi),
        TOOTHFUSE_VOLUME_SCHEME_UNIVERSAL => Ok(VolumeScheme::Universal),
        TOOTHFUSE_VOLUME_SCHEME_TOOTHFAIRY2 => Ok(VolumeScheme::ToothFairy2),
        TOOTHFUSE_VOLUME_SCHEME_DENTALSEGMENTATOR => Ok(VolumeScheme::DentalSegmentator),
        other => Err(Failure::invalid(format!(
            "volume scheme {other} is not one of TOOTHFUSE_VOLUME_SCHEME_FDI (0), UNIVERSAL (1), \
             TOOTHFAIRY2 (2), DENTALSEGMENTATOR (3)"
        ))),
    }
}

/// Adds the CBCT teeth of a label volume: every tooth label is surfaced (cavities filled,
/// partial-volume smoothing, surface nets at the 0.5 level, largest component) to a closed,
/// outward mesh in millimetres in the world frame of `voxel_to_world`, and added as the CBCT
/// tooth of its FDI number (replacing one held). All or nothing: on any failure the session is
/// unchanged. Labels under 20 mm^3 (fragments) and non-tooth labels of the scheme are skipped.
///
/// - `dims`: 3 `size_t`, voxels along i, j, k; labels are stored i fastest, then j, then k.
/// - `voxel_to_world`: 16 doubles, the row-major 4x4 matrix taking a voxel index (i, j, k, 1)
///   (voxel centres) to world millimetres (last row 0 0 0 1). The fused teeth come out in this
///   world frame (pass an LPS or a RAS matrix as the host expects). When NULL, `spacing` (3
///   doubles, mm, negative flips an axis) and `origin` (3 doubles, world position of voxel 0's
///   centre) give an axis-aligned grid; both must then be non-NULL.
/// - `labels`: `label_count` (= `dims[0] * dims[1] * dims[2]`) values of `label_type`, aligned for it.
/// - `scheme`: the numbering of the label values. With TOOTHFUSE_VOLUME_SCHEME_DENTALSEGMENTATOR
///   (one teeth label per jaw, no tooth numbers) the IOS teeth must be added first: each jaw's
///   IOS crowns are registered as one arch to its teeth mask, the mask is split into teeth
///   grown from the registered crowns, and each tooth is surfaced and added. Teeth whose split
///   cannot be trusted are not added; after a registration or fusion each tooth's split (its
///   share of contested voxels, or why it was refused) is among its warnings (registered teeth)
///   or in its skipped reason.
/// - `teeth_added_out`: when not NULL, receives the number of teeth added (on success only).
///
/// Fails with NULL_PARAMETER, INVALID_ARGUMENT (count mismatch, bad matrix, negative label, a
/// label the scheme does not know, two labels for one tooth, a DentalSegmentator-style per-jaw
/// volume under another scheme, IOS crowns of the other jaw only), UNIT_MISMATCH (voxel size
/// outside 0.001-10 mm), MISSING_DATA (no tooth label; no IOS teeth for a per-jaw volume) or
/// REGISTRATION_REJECTED (the IOS arch does not fit the per-jaw mask, or no tooth's split can
/// be trusted); the message names the label, voxel, jaw or tooth.
///
/// # Safety
/// `session` must be NULL or a live session; the pointers must be NULL or hold the documented
/// number of readable (or, for `teeth_added_out`, writable) values.
#[allow(clippy::too_many_arguments)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_add_label_volume(
    session: *mut toothfuse_session,
    dims: *const usize,
    voxel_to_world: *const f64,
    spacing: *const f64,
    origin: *const f64,
    labels: *const c_void,
    label_count: usize,
    label_type: toothfuse_label_type,
    scheme: toothfuse_volume_scheme,
    teeth_added_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &mut Session| -> FfiResult {
            if dims.is_null() {
                return Err(Failure::null("dims"));
            }
            // SAFETY: forwarded contract: 3 readable size_t at `dims`.
            let d = unsafe { slice_in(dims, 3, "dims") }?;
            let dims = [d[0], d[1], d[2]];
            let expected = dims[0].checked_mul(dims[1]).and_then(|n| n.checked_mul(dims[2]));
            if expected != Some(label_count) {
                return Err(Failure::invalid(format!(
                    "label_count {label_count} does not match dims {dims:?}"
                )));
            }
            let scheme = decode_volume_scheme(scheme)?;
            // SAFETY: forwarded contract on `labels`.
            let labels = unsafe { read_labels(labels, label_count, label_type) }?;
            let vol = if voxel_to_world.is_null() {
                if spacing.is_null() || origin.is_null() {
                    return Err(Failure::null(if spacing.is_null() { "spacing" } else { "origin" }));
                }
                // SAFETY: forwarded contract: 3 readable doubles each.
                let (sp, or) = unsafe { (slice_in(spacing, 3, "spacing")?, slice_in(origin, 3, "origin")?) };
                LabelVolume::with_spacing(dims, [sp[0], sp[1], sp[2]], [or[0], or[1], or[2]], Frame::Lps, labels)?
            } else {
                // SAFETY: forwarded contract: 16 readable doubles.
                let m = unsafe { slice_in(voxel_to_world, 16, "voxel_to_world") }?;
                let mut a = [0.0; 16];
                a.copy_from_slice(m);
                LabelVolume::new(dims, DMat4::from_cols_array(&a).transpose(), Frame::Lps, labels)?
            };
            let surfaced = s.add_label_volume(&vol, scheme, &SurfaceOptions::default())?;
            if !teeth_added_out.is_null() {
                // SAFETY: non-NULL; the caller guarantees it is writable.
                unsafe { write_out(teeth_added_out, surfaced.teeth.len(), "teeth_added_out") }?;
            }
            Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session_mut(session, body) }
    }
}
