//! The C ABI: the only unsafe code in the crate. The header `include/toothfuse.h` is generated
//! from this module by cbindgen (`cbindgen.toml`); never edit it by hand.
//!
//! Conventions (after rustls-ffi and meshoptimizer): opaque handles with `_new`/`_free` (free
//! is a no-op on NULL); the handle first (`const` when only read), inputs next, `*_out`
//! parameters last and written only on success; every fallible function returns a
//! [`toothfuse_status`], the detailed message is kept on the session
//! (`toothfuse_session_last_error`); vertex buffers are pointer + count + byte stride + scalar
//! type with `uint32_t` triangles, copied during the call and never kept. Every body runs inside
//! a panic boundary; a panic poisons the session.
//!
//! One file per handle family: [`session`] (lifetime, adding and listing teeth), [`mesh`]
//! (reading a tooth back), [`file`](mod@file) (reading mesh files), [`register`] (options, registration and its report), [`fuse`]
//! (one-call fuse, fused meshes and their quality), [`progress`] (the progress callback and
//! cancel), [`stages`] (cut and stitch as separate
//! stages, the cut roots), plus [`status`], [`version`] and the [`boundary`] helpers.

pub mod boundary;
pub mod file;
pub mod fuse;
pub mod mesh;
pub mod progress;
pub mod register;
pub mod session;
pub mod stages;
pub mod status;
pub mod version;
pub mod volume;

pub use file::*;
pub use fuse::*;
pub use mesh::*;
pub use progress::*;
pub use register::*;
pub use session::*;
pub use stages::*;
pub use status::*;
pub use version::*;
pub use volume::*;

#[cfg(test)]
mod abi_tests;
