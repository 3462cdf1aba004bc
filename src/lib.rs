//! # toothfuse
//!
//! Fuses a patient's intraoral scan (IOS: sharp crowns, no roots) with CBCT-derived tooth meshes
//! (whole teeth, blurry crowns) into one watertight mesh per tooth: IOS crown, CBCT root.
//!
//! The method follows *Best of Both Modalities* (centroid alignment, coarse point-to-plane ICP,
//! sequential fine registration, Dijkstra crown cut, recursive-interpolation stitching) and goes
//! beyond it where measured to help. See `ARCHITECTURE.md` for the module graph.
//!
//! The safe core (everything but [`ffi`]) has no unsafe code; [`ffi`] is the C ABI layer.
#![deny(unsafe_code)]

pub mod arch;
pub mod cut;
pub mod error;
pub mod eval;
pub mod fuse;
pub mod geom;
pub mod io;
pub mod mesh;
pub mod mesh_check;
mod par;
pub mod phantom;
pub mod pipeline;
pub mod progress;
mod radix;
pub mod register;
pub mod session;
pub mod stitch;
pub mod units;
pub mod volume;

#[allow(unsafe_code)]
pub mod ffi;

pub use error::{Error, ErrorKind, Result};
pub use geom::Rigid;
pub use mesh::TriMesh;
pub use par::{max_threads, with_max_threads};

/// The library version, from Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
