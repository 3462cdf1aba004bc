//! Registration through the C ABI: the size-prefixed options struct, `toothfuse_session_register`,
//! per-tooth transforms and report fields, warnings, skipped teeth and the report JSON.

use super::boundary::{Failure, FfiResult, check_out, ffi_panic_boundary, slice_out, write_out};
use super::session::{toothfuse_session, with_session, with_session_mut};
use super::status::toothfuse_status;
use crate::arch::check_fdi;
use crate::pipeline::PipelineOptions;
use crate::register::{OutputFrame, Preset, ToothRegistration};
use crate::session::Session;
use std::ffi::c_char;
use std::mem::{offset_of, size_of};

/// Option preset: one of the `TOOTHFUSE_PRESET_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_preset = u32;
/// The paper's method, faithfully (CA, CR, FR over tooth triples; its cut and stitch).
pub const TOOTHFUSE_PRESET_PAPER: toothfuse_preset = 0;
/// The measured-better default (robust ICP, crown-only centroids, guarded fine steps, ...).
pub const TOOTHFUSE_PRESET_DEFAULT: toothfuse_preset = 1;

/// Output frame of the fused meshes and reported transforms: one of `TOOTHFUSE_FRAME_*`.
#[allow(non_camel_case_types)]
pub type toothfuse_frame = u32;
/// The CBCT frame (fused teeth overlay the CBCT volume).
pub const TOOTHFUSE_FRAME_CBCT: toothfuse_frame = 0;
/// The IOS frame.
pub const TOOTHFUSE_FRAME_IOS: toothfuse_frame = 1;

/// Which per-tooth transform: one of the `TOOTHFUSE_TRANSFORM_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_transform = u32;
/// CBCT frame → output frame.
pub const TOOTHFUSE_TRANSFORM_CBCT_TO_OUTPUT: toothfuse_transform = 0;
/// IOS frame → output frame.
pub const TOOTHFUSE_TRANSFORM_IOS_TO_OUTPUT: toothfuse_transform = 1;
/// CBCT frame → IOS frame (independent of the output frame).
pub const TOOTHFUSE_TRANSFORM_CBCT_TO_IOS: toothfuse_transform = 2;

/// Options of `toothfuse_session_register` and `toothfuse_session_fuse`. Fill it with
/// `toothfuse_options_default` (which sets `struct_size`), then change fields. The ABI grows by
/// appending fields: a caller built against an older header passes its smaller `struct_size`
/// and the fields it does not know take their defaults.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct toothfuse_options {
    /// `sizeof(toothfuse_options)` as the caller was compiled.
    pub struct_size: usize,
    /// TOOTHFUSE_PRESET_DEFAULT (default) or TOOTHFUSE_PRESET_PAPER.
    pub preset: toothfuse_preset,
    /// TOOTHFUSE_FRAME_CBCT (default) or TOOTHFUSE_FRAME_IOS.
    pub frame: toothfuse_frame,
    /// 0 (default): data the registration finds questionable (mirrored, another patient, shifted
    /// or misnumbered labels: found by its gate before registering, or by crowns still off their
    /// CBCT teeth after it) are refused (TOOTHFUSE_STATUS_MIRRORED,
    /// TOOTHFUSE_STATUS_REGISTRATION_REJECTED) or their teeth skipped; 1: registered anyway, the
    /// findings then listed under `"questionable"` in the report JSON and as tooth warnings.
    /// Appended after `frame`: a caller whose `struct_size` ends before it gets 0.
    pub accept_questionable: u32,
}

impl Default for toothfuse_options {
    fn default() -> Self {
        Self {
            struct_size: size_of::<Self>(),
            preset: TOOTHFUSE_PRESET_DEFAULT,
            frame: TOOTHFUSE_FRAME_CBCT,
            accept_questionable: 0,
        }
    }
}

/// Smallest `struct_size` accepted (the first ABI version of the struct: up to `frame`).
const OPTIONS_MIN_SIZE: usize = offset_of!(toothfuse_options, frame) + size_of::<u32>();

/// End of `accept_questionable` (the second ABI version of the struct).
const OPTIONS_QUESTIONABLE_END: usize =
    offset_of!(toothfuse_options, accept_questionable) + size_of::<u32>();

/// Reads the caller's options (NULL = defaults) into pipeline options.
///
/// # Safety
/// `opts` must be NULL or point to at least `opts->struct_size` readable bytes.
pub(crate) unsafe fn read_options(opts: *const toothfuse_options) -> FfiResult<PipelineOptions> {
    let o = if opts.is_null() {
        toothfuse_options::default()
    } else {
        check_out(opts.cast_mut(), "options")?;
        // SAFETY: non-NULL and aligned (checked); the caller guarantees the first field is
        // readable.
        let size = unsafe { (*opts).struct_size };
        if size < OPTIONS_MIN_SIZE {
            return Err(Failure::invalid(format!(
                "options.struct_size {size} is below the smallest known layout ({OPTIONS_MIN_SIZE} \
                 bytes); fill the struct with toothfuse_options_default"
            )));
        }
        // The first layout's fields lie within OPTIONS_MIN_SIZE bytes; later fields are read
        // only when the caller's struct_size covers them.
        // SAFETY: at least OPTIONS_MIN_SIZE readable bytes (struct_size checked above), and
        // each later field only when within the caller's struct_size.
        unsafe {
            toothfuse_options {
                struct_size: size,
                preset: std::ptr::addr_of!((*opts).preset).read(),
                frame: std::ptr::addr_of!((*opts).frame).read(),
                accept_questionable: if size >= OPTIONS_QUESTIONABLE_END {
                    std::ptr::addr_of!((*opts).accept_questionable).read()
                } else {
                    0
                },
            }
        }
    };
    let preset = match o.preset {
        TOOTHFUSE_PRESET_PAPER => Preset::Paper,
        TOOTHFUSE_PRESET_DEFAULT => Preset::Default,
        p => {
            return Err(Failure::invalid(format!(
                "options.preset {p} is neither TOOTHFUSE_PRESET_PAPER (0) nor \
                 TOOTHFUSE_PRESET_DEFAULT (1)"
            )));
        }
    };
    let frame = match o.frame {
        TOOTHFUSE_FRAME_CBCT => OutputFrame::Cbct,
        TOOTHFUSE_FRAME_IOS => OutputFrame::Ios,
        f => {
            return Err(Failure::invalid(format!(
                "options.frame {f} is neither TOOTHFUSE_FRAME_CBCT (0) nor TOOTHFUSE_FRAME_IOS (1)"
            )));
        }
    };
    let accept_questionable = match o.accept_questionable {
        0 => false,
        1 => true,
        v => {
            return Err(Failure::invalid(format!(
                "options.accept_questionable {v} is neither 0 nor 1"
            )));
        }
    };
    let mut p = PipelineOptions::preset(preset).with_frame(frame);
    p.register.accept_questionable = accept_questionable;
    Ok(p)
}

/// Writes the default options (preset DEFAULT, frame CBCT, `struct_size` set) to `*options_out`.
///
/// # Safety
/// `options_out` must be NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_options_default(
    options_out: *mut toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contract on `options_out`.
        match unsafe { write_out(options_out, toothfuse_options::default(), "options_out") } {
            Ok(()) => toothfuse_status::Ok,
            Err(f) => f.status,
        }
    }
}

/// Registers the held CBCT teeth to the held IOS crowns (paper section 2.2; `options` NULL =
/// defaults) and keeps the result on the session, replacing an earlier one (and dropping fused
/// results). IOS repair (`toothfuse_session_set_ios_repair`) has already applied when the crowns
/// were added. Fails with MISSING_DATA (the message names the teeth) when fewer than three
/// teeth are in both modalities or their centroids are collinear; on any failure the previous
/// results are kept. Teeth in one modality only are listed by `toothfuse_session_skipped`.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_register(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
) -> toothfuse_status {
    ffi_panic_boundary! {
        // SAFETY: forwarded contracts on `session` and `options`.
        unsafe {
            with_options(session, options, |s, o| {
                s.register(o)?;
                Ok(())
            })
        }
    }
}

/// The shared body of the entry points that take an options struct: reads `options` (NULL =
/// defaults) and runs `run` on the session.
///
/// # Safety
/// `session` must be NULL or a live session; `options` NULL or a valid options struct.
pub(crate) unsafe fn with_options(
    session: *mut toothfuse_session,
    options: *const toothfuse_options,
    run: impl FnOnce(&mut Session, &PipelineOptions) -> FfiResult,
) -> toothfuse_status {
    let body = |s: &mut Session| -> FfiResult {
        // SAFETY: forwarded contract on `options`.
        let opts = unsafe { read_options(options) }?;
        run(s, &opts)
    };
    // SAFETY: forwarded contract on `session`.
    unsafe { with_session_mut(session, body) }
}

/// The registration of tooth `fdi`, or WRONG_STATE / MISSING_DATA naming what is missing.
fn registered(s: &Session, fdi: i32) -> FfiResult<&ToothRegistration> {
    let key = check_fdi(fdi)?;
    let r = s.registration()?;
    r.teeth.get(&key).ok_or_else(|| {
        Failure::new(
            toothfuse_status::MissingData,
            format!(
                "tooth {fdi} is not registered (registered: {:?})",
                r.teeth.keys().collect::<Vec<_>>()
            ),
        )
    })
}

/// Copies a list of FDI numbers with the count-query pattern of `toothfuse_session_list_teeth`.
///
/// # Safety
/// `fdi_out` must have room for `capacity` values; `count_out` NULL or writable.
pub(crate) unsafe fn copy_fdis(
    fdis: &[u8],
    fdi_out: *mut i32,
    capacity: usize,
    count_out: *mut usize,
) -> FfiResult {
    check_out(count_out, "count_out")?;
    if capacity < fdis.len() {
        return Err(Failure::new(
            toothfuse_status::BufferTooSmall,
            format!("{} teeth but `fdi_out` has room for {capacity}", fdis.len()),
        ));
    }
    // SAFETY: forwarded contract: room for `capacity` >= fdis.len() values.
    let out = unsafe { slice_out(fdi_out, fdis.len(), "fdi_out") }?;
    for (o, f) in out.iter_mut().zip(fdis) {
        *o = i32::from(*f);
    }
    // SAFETY: forwarded contract on `count_out`.
    unsafe { write_out(count_out, fdis.len(), "count_out") }
}

/// Copies the FDI numbers of the registered teeth, ascending, into `fdi_out` (room for
/// `capacity`; NULL allowed when 0) and writes how many to `*count_out`. BUFFER_TOO_SMALL
/// (nothing written) when `capacity` is below the count; room for 52 (every FDI number) always
/// suffices. WRONG_STATE before a register or fuse.
///
/// # Safety
/// `session` must be NULL or a live session; `fdi_out` must have room for `capacity` `int32_t`;
/// `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_registered_teeth(
    session: *const toothfuse_session,
    fdi_out: *mut i32,
    capacity: usize,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            let fdis: Vec<u8> = s.registration()?.teeth.keys().copied().collect();
            // SAFETY: forwarded contract on the outputs.
            unsafe { copy_fdis(&fdis, fdi_out, capacity, count_out) }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes the 4×4 rigid transform `which` (TOOTHFUSE_TRANSFORM_*) of registered tooth `fdi` to
/// `out16`, row-major (`out16[4*r + c]`; the last row is 0 0 0 1; translation in `out16[3]`,
/// `out16[7]`, `out16[11]`, millimetres). WRONG_STATE before a register or fuse; MISSING_DATA
/// for a tooth that was not registered.
///
/// # Safety
/// `session` must be NULL or a live session; `out16` NULL or room for 16 doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_transform(
    session: *const toothfuse_session,
    fdi: i32,
    which: toothfuse_transform,
    out16: *mut f64,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(out16, "out16")?;
            let t = registered(s, fdi)?;
            let m = match which {
                TOOTHFUSE_TRANSFORM_CBCT_TO_OUTPUT => t.cbct_to_output,
                TOOTHFUSE_TRANSFORM_IOS_TO_OUTPUT => t.ios_to_output,
                TOOTHFUSE_TRANSFORM_CBCT_TO_IOS => t.cbct_to_ios,
                w => {
                    return Err(Failure::invalid(format!(
                        "transform {w} is not a TOOTHFUSE_TRANSFORM_* value (0, 1 or 2)"
                    )));
                }
            }
            .to_row_major();
            // SAFETY: forwarded contract: room for 16 doubles.
            let out = unsafe { slice_out(out16, 16, "out16") }?;
            out.copy_from_slice(&m);
            Ok(())
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Registration report of one tooth.
#[repr(C)]
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct toothfuse_tooth_report {
    /// The paper's surface distance SD: mean distance (mm) from the registered IOS crown points to
    /// the CBCT surface.
    pub sd_mm: f64,
    /// RMS of the same distances (mm).
    pub rmse_mm: f64,
    /// Fraction of IOS points within the inlier distance of the CBCT surface.
    pub inlier_fraction: f64,
    /// Size (mm) of the fine stage's correction at the crown.
    pub fine_correction_mm: f64,
    /// ICP iterations.
    pub iterations: usize,
    /// Number of warnings (read each with `toothfuse_session_tooth_warning`).
    pub warning_count: usize,
    /// The ICP converged.
    pub converged: bool,
}

/// Writes the registration report of tooth `fdi` to `*report_out`. After a fuse, the warnings
/// counted include the fusion's. WRONG_STATE before a register or fuse; MISSING_DATA for a tooth
/// that was not registered.
///
/// # Safety
/// `session` must be NULL or a live session; `report_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_tooth_report(
    session: *const toothfuse_session,
    fdi: i32,
    report_out: *mut toothfuse_tooth_report,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(report_out, "report_out")?;
            let t = registered(s, fdi)?;
            let r = toothfuse_tooth_report {
                sd_mm: t.sd_mm,
                rmse_mm: t.rmse_mm,
                inlier_fraction: t.inlier_fraction,
                fine_correction_mm: t.fine_correction_mm,
                iterations: t.iterations,
                warning_count: s.notes().warnings.get(&t.fdi).map_or(0, Vec::len),
                converged: t.converged,
            };
            // SAFETY: forwarded contract on `report_out`.
            unsafe { write_out(report_out, r, "report_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes warning `index` (0-based, below the report's `warning_count`) of tooth `fdi` to
/// `*warning_out`: a NUL-terminated string borrowed from the session, valid until the session's
/// teeth or results change or it is freed; never free it. INDEX_OUT_OF_BOUNDS past the last.
///
/// # Safety
/// `session` must be NULL or a live session; `warning_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_tooth_warning(
    session: *const toothfuse_session,
    fdi: i32,
    index: usize,
    warning_out: *mut *const c_char,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(warning_out, "warning_out")?;
            let t = registered(s, fdi)?;
            let ws = s.notes().warnings.get(&t.fdi).map_or(&[][..], Vec::as_slice);
            let w = ws.get(index).ok_or_else(|| {
                Failure::new(
                    toothfuse_status::IndexOutOfBounds,
                    format!("tooth {fdi} has {} warnings; index {index} is past them", ws.len()),
                )
            })?;
            // SAFETY: forwarded contract on `warning_out`.
            unsafe { write_out(warning_out, w.as_ptr(), "warning_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes the number of skipped teeth of the last result to `*count_out`: after a register,
/// teeth in one modality only; after a fuse, also teeth whose fusion failed. WRONG_STATE before a
/// register or fuse.
///
/// # Safety
/// `session` must be NULL or a live session; `count_out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_skipped_count(
    session: *const toothfuse_session,
    count_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(count_out, "count_out")?;
            s.registration()?;
            // SAFETY: forwarded contract on `count_out`.
            unsafe { write_out(count_out, s.notes().skipped.len(), "count_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Writes skipped tooth `index` (0-based, FDI order): its FDI number to `*fdi_out` and the
/// reason (NUL-terminated, borrowed as for `toothfuse_session_tooth_warning`) to `*reason_out`.
/// INDEX_OUT_OF_BOUNDS past the last; WRONG_STATE before a register or fuse.
///
/// # Safety
/// `session` must be NULL or a live session; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_skipped(
    session: *const toothfuse_session,
    index: usize,
    fdi_out: *mut i32,
    reason_out: *mut *const c_char,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(fdi_out, "fdi_out")?;
            check_out(reason_out, "reason_out")?;
            s.registration()?;
            let sk = &s.notes().skipped;
            let (fdi, reason) = sk.get(index).ok_or_else(|| {
                Failure::new(
                    toothfuse_status::IndexOutOfBounds,
                    format!("{} skipped teeth; index {index} is past them", sk.len()),
                )
            })?;
            // SAFETY: forwarded contract on the outputs.
            unsafe {
                write_out(fdi_out, i32::from(*fdi), "fdi_out")?;
                write_out(reason_out, reason.as_ptr(), "reason_out")
            }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}

/// Copies the report JSON of the last result (after a fuse: the `toothfuse fuse` report.json;
/// after a register: the `toothfuse register` report) into `buf`, NUL-terminated, and writes its
/// length without the NUL to `*len_out`. Size query: `buf` NULL and `capacity` 0 writes only
/// `*len_out`. BUFFER_TOO_SMALL (nothing written) when `capacity < length + 1`. WRONG_STATE
/// before a register or fuse.
///
/// # Safety
/// `session` must be NULL or a live session; `buf` room for `capacity` bytes; `len_out` NULL or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_report_json(
    session: *const toothfuse_session,
    buf: *mut c_char,
    capacity: usize,
    len_out: *mut usize,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let body = |s: &Session| -> FfiResult {
            check_out(len_out, "len_out")?;
            let json = s.report_json()?;
            let n = json.len();
            if !(buf.is_null() && capacity == 0) {
                if capacity < n + 1 {
                    return Err(Failure::new(
                        toothfuse_status::BufferTooSmall,
                        format!("report JSON needs {} bytes (with the NUL); buffer has {capacity}", n + 1),
                    ));
                }
                // SAFETY: forwarded contract: room for `capacity` >= n + 1 bytes.
                let out = unsafe { slice_out(buf.cast::<u8>(), n + 1, "buf") }?;
                out[..n].copy_from_slice(json.as_bytes());
                out[n] = 0;
            }
            // SAFETY: forwarded contract on `len_out`.
            unsafe { write_out(len_out, n, "len_out") }
        };
        // SAFETY: forwarded contract on `session`.
        unsafe { with_session(session, body) }
    }
}
