//! The panic boundary and the raw-pointer helpers every exported function goes through.
//!
//! Every `extern "C"` body runs inside `ffi_panic_boundary!` (after rustls-ffi's macro of the
//! same name): a panic never unwinds into C; it becomes `TOOTHFUSE_STATUS_PANIC` (or a NULL /
//! zero result for functions that return no status). Functions on a session additionally run
//! their body through `with_session`/`with_session_mut` (in `ffi::session`), which record the
//! detailed message and poison the session after a caught panic.

use super::status::toothfuse_status;
use std::any::Any;
use std::ffi::{c_char, c_void};
use std::mem::{align_of, size_of};

/// What an exported function returns when its body panicked.
pub trait PanicValue {
    /// The value returned to C after a caught panic.
    fn on_panic() -> Self;
}

impl PanicValue for toothfuse_status {
    fn on_panic() -> Self {
        toothfuse_status::Panic
    }
}

impl PanicValue for *const c_char {
    fn on_panic() -> Self {
        std::ptr::null()
    }
}

impl PanicValue for u32 {
    fn on_panic() -> Self {
        0
    }
}

impl PanicValue for () {
    fn on_panic() -> Self {}
}

/// Runs the body, catching any panic and returning [`PanicValue::on_panic`] instead.
macro_rules! ffi_panic_boundary {
    ( $($body:tt)* ) => {
        match ::std::panic::catch_unwind(::std::panic::AssertUnwindSafe(|| { $($body)* })) {
            Ok(value) => value,
            Err(_) => $crate::ffi::boundary::PanicValue::on_panic(),
        }
    };
}
pub(crate) use ffi_panic_boundary;

/// A failed call: the status to return and the detailed message to keep on the session.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// Status returned to C.
    pub status: toothfuse_status,
    /// Detailed message (names the tooth, vertex or face at fault).
    pub message: String,
}

impl Failure {
    /// A failure with an explicit status.
    pub fn new(status: toothfuse_status, message: impl Into<String>) -> Self {
        Self {
            status,
            message: message.into(),
        }
    }

    /// `TOOTHFUSE_STATUS_NULL_PARAMETER` for the parameter `name`.
    pub fn null(name: &str) -> Self {
        Self::new(
            toothfuse_status::NullParameter,
            format!("parameter `{name}` is NULL"),
        )
    }

    /// `TOOTHFUSE_STATUS_INVALID_ARGUMENT` with a message.
    pub fn invalid(message: impl Into<String>) -> Self {
        Self::new(toothfuse_status::InvalidArgument, message)
    }
}

impl From<crate::Error> for Failure {
    fn from(e: crate::Error) -> Self {
        Self::new(e.kind().into(), e.to_string())
    }
}

/// Result of a call body.
pub type FfiResult<T = ()> = Result<T, Failure>;

/// The message of a panic payload, if it is a string.
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

/// Checks that `ptr` may be read or written as `len` values of `T`: non-NULL (unless
/// `len == 0`), aligned for `T`, and `len * size_of::<T>()` within `isize::MAX`.
fn check_region<T>(ptr: *const T, len: usize, name: &str) -> FfiResult<bool> {
    if len == 0 {
        return Ok(false);
    }
    if ptr.is_null() {
        return Err(Failure::new(
            toothfuse_status::NullParameter,
            format!("parameter `{name}` is NULL but {len} elements were announced"),
        ));
    }
    if !(ptr as usize).is_multiple_of(align_of::<T>()) {
        return Err(Failure::invalid(format!(
            "parameter `{name}` is not aligned to {} bytes",
            align_of::<T>()
        )));
    }
    match len.checked_mul(size_of::<T>()) {
        Some(bytes) if bytes <= isize::MAX as usize => Ok(true),
        _ => Err(Failure::invalid(format!(
            "parameter `{name}`: {len} elements overflow the address space"
        ))),
    }
}

/// Borrows a caller's input array of `len` values of `T` (NULL allowed when `len == 0`).
///
/// # Safety
/// When `len > 0` and `ptr` is not NULL, `ptr` must point to `len` initialised values of `T`
/// that stay valid and unmodified for `'a`.
pub unsafe fn slice_in<'a, T>(ptr: *const T, len: usize, name: &str) -> FfiResult<&'a [T]> {
    if !check_region(ptr, len, name)? {
        return Ok(&[]);
    }
    // SAFETY: check_region verified non-NULL, alignment and size; the caller guarantees that
    // `len` initialised values live at `ptr` for `'a`.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// Borrows `len` bytes of a caller's untyped input buffer (NULL allowed when `len == 0`).
///
/// # Safety
/// As [`slice_in`] with `T = u8`.
pub unsafe fn bytes_in<'a>(ptr: *const c_void, len: usize, name: &str) -> FfiResult<&'a [u8]> {
    // SAFETY: forwarded contract: `len` readable bytes at `ptr`.
    unsafe { slice_in(ptr.cast::<u8>(), len, name) }
}

/// Borrows a caller's output array of `len` values of `T` (NULL allowed when `len == 0`).
///
/// # Safety
/// When `len > 0` and `ptr` is not NULL, `ptr` must point to `len` writable values of `T`, not
/// aliased by anything else during `'a`.
pub unsafe fn slice_out<'a, T>(ptr: *mut T, len: usize, name: &str) -> FfiResult<&'a mut [T]> {
    if !check_region(ptr.cast_const(), len, name)? {
        return Ok(&mut []);
    }
    // SAFETY: check_region verified non-NULL, alignment and size; the caller guarantees `len`
    // writable, unaliased values at `ptr` for `'a`.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

/// Copies `values` into a caller's output array `out` (parameter `name`, room for `capacity`);
/// BUFFER_TOO_SMALL (nothing written) when it is short, as "`subject`: n `what` to copy but the
/// buffer has room for `capacity`".
///
/// # Safety
/// As [`slice_out`] for `values.len()` values when `capacity >= values.len()`.
pub unsafe fn copy_out<T: Copy>(
    values: &[T],
    out: *mut T,
    capacity: usize,
    name: &str,
    subject: &str,
    what: &str,
) -> FfiResult {
    let n = values.len();
    if capacity < n {
        return Err(Failure::new(
            toothfuse_status::BufferTooSmall,
            format!("{subject}: {n} {what} to copy but the buffer has room for {capacity}"),
        ));
    }
    // SAFETY: the caller guarantees room for `capacity >= n` values.
    let dst = unsafe { slice_out(out, n, name) }?;
    dst.copy_from_slice(values);
    Ok(())
}

/// Checks an output pointer for one `T` (non-NULL, aligned) without writing it.
pub fn check_out<T>(ptr: *mut T, name: &str) -> FfiResult<()> {
    if ptr.is_null() {
        return Err(Failure::null(name));
    }
    if !(ptr as usize).is_multiple_of(align_of::<T>()) {
        return Err(Failure::invalid(format!(
            "parameter `{name}` is not aligned to {} bytes",
            align_of::<T>()
        )));
    }
    Ok(())
}

/// Writes `value` through an output pointer checked by [`check_out`].
///
/// # Safety
/// `ptr` must be valid for a write of one `T`.
pub unsafe fn write_out<T>(ptr: *mut T, value: T, name: &str) -> FfiResult<()> {
    check_out(ptr, name)?;
    // SAFETY: non-NULL and aligned (checked above); the caller guarantees it is writable.
    unsafe { ptr.write(value) };
    Ok(())
}
