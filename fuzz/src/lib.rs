//! Shared helpers of the fuzz targets: the invariants every successful read must satisfy, and
//! the tiny synthetic jaw plus the byte-driven mutations of the C-ABI fuse target.

pub mod jaw;

use toothfuse::mesh::LabeledMesh;

/// Asserts what every reader promises on success: finite coordinates, triangle indices within
/// the vertex list, and label arrays as long as what they label.
pub fn check_read(m: &LabeledMesh) {
    let n = m.mesh.positions.len();
    assert!(
        m.mesh.positions.iter().all(|p| p.is_finite()),
        "non-finite vertex accepted"
    );
    for t in &m.mesh.triangles {
        assert!(
            t.iter().all(|&v| (v as usize) < n),
            "triangle {t:?} out of {n} vertices"
        );
    }
    if let Some(l) = &m.vertex_labels {
        assert_eq!(l.len(), n, "vertex labels");
    }
    if let Some(l) = &m.face_labels {
        assert_eq!(l.len(), m.mesh.triangles.len(), "face labels");
    }
}
