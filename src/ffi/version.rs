//! Library and ABI versions. The header macros below are checked against Cargo.toml by a test.

use super::boundary::ffi_panic_boundary;
use std::ffi::c_char;

/// Major version of the library (the shared library's SOVERSION).
pub const TOOTHFUSE_VERSION_MAJOR: u32 = 0;
/// Minor version of the library.
pub const TOOTHFUSE_VERSION_MINOR: u32 = 1;
/// Patch version of the library.
pub const TOOTHFUSE_VERSION_PATCH: u32 = 0;
/// Version of the C ABI described by this header; `toothfuse_abi_version()` returns the
/// library's. Bumped on every incompatible change to a function, struct or enum value.
pub const TOOTHFUSE_ABI_VERSION: u32 = 2;

/// The library version as a static string, "MAJOR.MINOR.PATCH". Never NULL; never free it.
/// Thread-safe.
#[unsafe(no_mangle)]
pub extern "C" fn toothfuse_version() -> *const c_char {
    ffi_panic_boundary! {
        concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
    }
}

/// The ABI version the library implements; compare with TOOTHFUSE_ABI_VERSION to detect a
/// header/library mismatch. Thread-safe.
#[unsafe(no_mangle)]
pub extern "C" fn toothfuse_abi_version() -> u32 {
    ffi_panic_boundary! { TOOTHFUSE_ABI_VERSION }
}
