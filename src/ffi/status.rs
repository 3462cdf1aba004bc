//! The status code every fallible C function returns, its static strings, and the one mapping
//! from [`crate::ErrorKind`].

use crate::ErrorKind;
use std::ffi::c_char;

/// Result of every fallible `toothfuse_*` function. `TOOTHFUSE_STATUS_OK` is 0; any other value is
/// a failure whose detailed message is available from `toothfuse_session_last_error` when the
/// function took a session. New values may be added in later ABI versions: treat an unknown value
/// as a failure.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub enum toothfuse_status {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL.
    NullParameter = 1,
    /// An argument is out of its documented range or inconsistent with another (bad stride,
    /// unknown enum value, index count not a multiple of 3, non-FDI number or label, ...).
    InvalidArgument = 2,
    /// A vertex coordinate is NaN or infinite.
    NonFinite = 3,
    /// A triangle refers to a vertex that does not exist.
    IndexOutOfBounds = 4,
    /// A mesh is not a valid 2-manifold where one is required, is not closed where it must be,
    /// or has degenerate or duplicate triangles.
    NotManifold = 5,
    /// Units look wrong (metres instead of millimetres, or wildly different scales).
    UnitMismatch = 6,
    /// Required data is missing (for example the requested tooth is not in the session).
    MissingData = 7,
    /// An iterative method did not converge.
    DidNotConverge = 8,
    /// The caller's output buffer is too small; query the required size first.
    BufferTooSmall = 9,
    /// The operation needs an earlier step first.
    WrongState = 10,
    /// A file could not be read or written, or its content is malformed.
    Io = 11,
    /// An internal error (a Rust panic) was caught at the boundary; the session is now poisoned.
    Panic = 12,
    /// The session was poisoned by an earlier panic; free it and start a new one.
    Poisoned = 13,
    /// One modality is a mirror image of the other (x -> -x, or an LPS/RAS conversion applied to
    /// one modality only); the message names the evidence. Nothing was registered.
    Mirrored = 14,
    /// The data were refused: the IOS and the CBCT do not belong together (another patient, the
    /// other jaw, tooth numbers shifted along the arch), found by the registration gate before
    /// registering or, on an arch of any length, by the crowns still lying off their CBCT teeth
    /// after the full registration; the message names the likely cause. Set
    /// `accept_questionable` in the options to register anyway.
    RegistrationRejected = 15,
    /// The session's progress callback (`toothfuse_session_set_progress`) asked the call to
    /// stop; the session keeps what it held before the call.
    Cancelled = 16,
}

impl From<ErrorKind> for toothfuse_status {
    fn from(kind: ErrorKind) -> Self {
        match kind {
            ErrorKind::InvalidArgument => Self::InvalidArgument,
            ErrorKind::NonFinite => Self::NonFinite,
            ErrorKind::IndexOutOfBounds => Self::IndexOutOfBounds,
            ErrorKind::NotManifold => Self::NotManifold,
            ErrorKind::UnitMismatch => Self::UnitMismatch,
            ErrorKind::MissingData => Self::MissingData,
            ErrorKind::DidNotConverge => Self::DidNotConverge,
            ErrorKind::Io => Self::Io,
            ErrorKind::WrongState => Self::WrongState,
            ErrorKind::Mirrored => Self::Mirrored,
            ErrorKind::RegistrationRejected => Self::RegistrationRejected,
            ErrorKind::Cancelled => Self::Cancelled,
        }
    }
}

impl toothfuse_status {
    /// Every status, in numeric order.
    pub(crate) const ALL: [toothfuse_status; 17] = [
        Self::Ok,
        Self::NullParameter,
        Self::InvalidArgument,
        Self::NonFinite,
        Self::IndexOutOfBounds,
        Self::NotManifold,
        Self::UnitMismatch,
        Self::MissingData,
        Self::DidNotConverge,
        Self::BufferTooSmall,
        Self::WrongState,
        Self::Io,
        Self::Panic,
        Self::Poisoned,
        Self::Mirrored,
        Self::RegistrationRejected,
        Self::Cancelled,
    ];

    /// The status with numeric value `v`, if any.
    pub fn from_u32(v: u32) -> Option<Self> {
        Self::ALL.get(v as usize).copied()
    }

    /// A short, static, NUL-terminated description.
    pub fn message(self) -> &'static str {
        match self {
            Self::Ok => "ok\0",
            Self::NullParameter => "a required pointer argument is NULL\0",
            Self::InvalidArgument => "invalid argument\0",
            Self::NonFinite => "non-finite coordinate (NaN or infinity)\0",
            Self::IndexOutOfBounds => "triangle index out of bounds\0",
            Self::NotManifold => "mesh is not a closed/valid 2-manifold where one is required\0",
            Self::UnitMismatch => "unit mismatch (millimetres expected)\0",
            Self::MissingData => "missing data\0",
            Self::DidNotConverge => "did not converge\0",
            Self::BufferTooSmall => "output buffer too small\0",
            Self::WrongState => "wrong state: an earlier step is needed first\0",
            Self::Io => "file input/output error\0",
            Self::Panic => "internal error (panic caught); the session is poisoned\0",
            Self::Poisoned => "session poisoned by an earlier internal error; free it\0",
            Self::Mirrored => "one modality is a mirror image of the other\0",
            Self::RegistrationRejected => {
                "registration rejected: the IOS and the CBCT do not belong together\0"
            }
            Self::Cancelled => "cancelled by the progress callback\0",
        }
    }
}

/// A static, NUL-terminated English description of `status` (any value is accepted; unknown
/// values give "unknown status"). Never NULL; never free it. Thread-safe.
#[unsafe(no_mangle)]
pub extern "C" fn toothfuse_status_string(status: u32) -> *const c_char {
    let s = toothfuse_status::from_u32(status)
        .map(toothfuse_status::message)
        .unwrap_or("unknown status\0");
    s.as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_and_strings() {
        for (i, s) in toothfuse_status::ALL.iter().enumerate() {
            assert_eq!(*s as u32, i as u32);
            assert_eq!(toothfuse_status::from_u32(i as u32), Some(*s));
            let m = s.message();
            assert!(m.ends_with('\0') && m.len() > 2 && !m[..m.len() - 1].contains('\0'));
        }
        assert_eq!(toothfuse_status::from_u32(17), None);
        assert_eq!(
            toothfuse_status::from(ErrorKind::NotManifold),
            toothfuse_status::NotManifold
        );
    }
}
