//! The crate's one error type. Every fallible core function returns [`Result`].
//!
//! Each variant names what is at fault (tooth, vertex, face) so the message can be shown to a
//! user as is; [`Error::kind`] gives the coarse category the C ABI maps to a status code.

use std::fmt;

/// Result alias used throughout the core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Coarse error category; the C ABI maps each to one status code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// An argument is out of its documented range or inconsistent with another.
    InvalidArgument,
    /// A coordinate is NaN or infinite.
    NonFinite,
    /// A triangle refers to a vertex that does not exist.
    IndexOutOfBounds,
    /// The mesh is not a valid 2-manifold where one is required (or has degenerate/duplicate faces).
    NotManifold,
    /// Units look wrong (metres instead of millimetres, or wildly different scales).
    UnitMismatch,
    /// Too few teeth present in both modalities (or otherwise missing data).
    MissingData,
    /// An iterative method did not converge.
    DidNotConverge,
    /// A file could not be read or written, or its content is malformed.
    Io,
    /// The operation needs an earlier step first (for example fusing before registering).
    WrongState,
    /// One modality is a mirror image of the other (or of its own tooth numbering).
    Mirrored,
    /// The registration gate found that the IOS and the CBCT do not belong together.
    RegistrationRejected,
    /// The caller's progress callback asked the call to stop.
    Cancelled,
}

/// Everything that can go wrong in toothfuse. Messages say what is at fault and how to fix it.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// An argument is out of range; the message names which and why.
    InvalidArgument(String),
    /// A non-finite coordinate at `vertex`.
    NonFinite {
        /// Index of the offending vertex in the input buffer.
        vertex: usize,
    },
    /// Triangle `face` refers to vertex `index`, but only `vertex_count` vertices exist.
    IndexOutOfBounds {
        /// Index of the offending triangle.
        face: usize,
        /// The out-of-range vertex index it holds.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// Triangle `face` repeats a vertex or has zero area.
    DegenerateFace {
        /// Index of the offending triangle.
        face: usize,
    },
    /// Triangle `face` uses the same three vertices as triangle `first`.
    DuplicateFace {
        /// Index of the later duplicate.
        face: usize,
        /// Index of the first occurrence.
        first: usize,
    },
    /// Edge (`a`, `b`) is used by `faces` triangles (more than two), or twice in the same direction.
    NonManifoldEdge {
        /// First vertex of the edge.
        a: u32,
        /// Second vertex of the edge.
        b: u32,
        /// Number of triangles using the edge.
        faces: usize,
    },
    /// Vertex `vertex` joins two or more separate fans of triangles (a "bow tie").
    NonManifoldVertex {
        /// Index of the offending vertex.
        vertex: usize,
    },
    /// A closed surface was required but the mesh has `boundary_edges` open edges.
    NotClosed {
        /// Number of boundary edges found.
        boundary_edges: usize,
    },
    /// Units look wrong; the message gives the measured extent.
    UnitMismatch(String),
    /// Required data is missing (for example fewer than three teeth in both modalities).
    MissingData(String),
    /// An iterative method stopped before converging.
    DidNotConverge(String),
    /// File input/output failed or the content is malformed.
    Io(String),
    /// The operation needs an earlier step first.
    WrongState(String),
    /// One modality is a mirror image of the other; the message names the evidence.
    Mirrored(String),
    /// The IOS and the CBCT do not belong together (another patient, the other jaw, shifted
    /// tooth numbers); the message names the likely cause.
    RegistrationRejected(String),
    /// The caller's progress callback ([`crate::progress::with_progress`]) asked the call to
    /// stop; the message names the stage.
    Cancelled(String),
    /// An error with what the caller can do about it (e.g. an IOS crown refused as given, with
    /// how to have crowns repaired on entry); of the kind of `inner`.
    WithRemedy {
        /// What went wrong.
        inner: Box<Error>,
        /// What the caller can do, as a clause that follows the error's own text.
        remedy: String,
    },
    /// An error that concerns one tooth, by FDI number.
    Tooth {
        /// FDI number of the tooth.
        fdi: u8,
        /// What went wrong with it.
        inner: Box<Error>,
    },
}

impl Error {
    /// The coarse category of this error.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::InvalidArgument(_) => ErrorKind::InvalidArgument,
            Error::NonFinite { .. } => ErrorKind::NonFinite,
            Error::IndexOutOfBounds { .. } => ErrorKind::IndexOutOfBounds,
            Error::DegenerateFace { .. }
            | Error::DuplicateFace { .. }
            | Error::NonManifoldEdge { .. }
            | Error::NonManifoldVertex { .. }
            | Error::NotClosed { .. } => ErrorKind::NotManifold,
            Error::UnitMismatch(_) => ErrorKind::UnitMismatch,
            Error::MissingData(_) => ErrorKind::MissingData,
            Error::DidNotConverge(_) => ErrorKind::DidNotConverge,
            Error::Io(_) => ErrorKind::Io,
            Error::WrongState(_) => ErrorKind::WrongState,
            Error::Mirrored(_) => ErrorKind::Mirrored,
            Error::RegistrationRejected(_) => ErrorKind::RegistrationRejected,
            Error::Cancelled(_) => ErrorKind::Cancelled,
            Error::WithRemedy { inner, .. } | Error::Tooth { inner, .. } => inner.kind(),
        }
    }

    /// Wraps this error with the FDI number of the tooth it concerns.
    pub fn in_tooth(self, fdi: u8) -> Error {
        match self {
            e @ Error::Tooth { .. } => e,
            // The remedy stays last: "tooth 11: <error>; <remedy>".
            Error::WithRemedy { inner, remedy } => Error::WithRemedy {
                inner: Box::new(inner.in_tooth(fdi)),
                remedy,
            },
            e => Error::Tooth {
                fdi,
                inner: Box::new(e),
            },
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidArgument(m) => write!(f, "invalid argument: {m}"),
            Error::NonFinite { vertex } => {
                write!(
                    f,
                    "vertex {vertex} has a non-finite coordinate (NaN or infinity)"
                )
            }
            Error::IndexOutOfBounds {
                face,
                index,
                vertex_count,
            } => write!(
                f,
                "face {face} refers to vertex {index}, but the mesh has only {vertex_count} vertices"
            ),
            Error::DegenerateFace { face } => {
                write!(
                    f,
                    "face {face} is degenerate (repeated vertex or zero area)"
                )
            }
            Error::DuplicateFace { face, first } => {
                write!(
                    f,
                    "face {face} duplicates face {first} (same three vertices)"
                )
            }
            Error::NonManifoldEdge { a, b, faces } => write!(
                f,
                "edge ({a}, {b}) is non-manifold: used by {faces} faces or twice in one direction"
            ),
            Error::NonManifoldVertex { vertex } => write!(
                f,
                "vertex {vertex} is non-manifold: it joins separate fans of faces"
            ),
            Error::NotClosed { boundary_edges } => write!(
                f,
                "mesh is not closed: {boundary_edges} boundary edges (a closed tooth surface is required)"
            ),
            Error::UnitMismatch(m) => write!(f, "unit mismatch: {m}"),
            Error::MissingData(m) => write!(f, "missing data: {m}"),
            Error::DidNotConverge(m) => write!(f, "did not converge: {m}"),
            Error::Io(m) => write!(f, "i/o: {m}"),
            Error::WrongState(m) => write!(f, "wrong state: {m}"),
            Error::Mirrored(m) => write!(f, "mirrored: {m}"),
            Error::RegistrationRejected(m) => write!(f, "registration rejected: {m}"),
            Error::Cancelled(m) => write!(f, "cancelled: {m}"),
            Error::WithRemedy { inner, remedy } => write!(f, "{inner}; {remedy}"),
            Error::Tooth { fdi, inner } => write!(f, "tooth {fdi}: {inner}"),
        }
    }
}

impl std::error::Error for Error {}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Io(e.to_string())
    }
}
