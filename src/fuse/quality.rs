//! Per-tooth quality report of a fused mesh: topology (closed, manifold, components), volume,
//! degenerate and self-intersecting faces, band triangle angles and edge lengths.

use crate::mesh::TriMesh;
use crate::mesh_check;
use serde::Serialize;

/// Quality of one fused tooth.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ToothQuality {
    /// Every edge in exactly two faces.
    pub closed: bool,
    /// No non-manifold edge or vertex.
    pub manifold: bool,
    /// Edges used by one face.
    pub boundary_edges: usize,
    /// Edges used by more than two faces (or twice in one direction).
    pub non_manifold_edges: usize,
    /// Vertices joining separate fans.
    pub non_manifold_vertices: usize,
    /// Connected components.
    pub components: usize,
    /// Enclosed volume (mm³), positive when outward oriented.
    pub volume: f64,
    /// Faces with a repeated index or exactly collinear corners.
    pub degenerate_faces: usize,
    /// Intersecting face pairs (exact test), if checked.
    pub self_intersections: Option<usize>,
    /// Smallest angle (degrees) in any band triangle.
    pub band_min_angle_deg: f64,
    /// Band edge lengths: minimum, mean, maximum (mm).
    pub band_edge_min: f64,
    /// Mean band edge length (mm).
    pub band_edge_mean: f64,
    /// Maximum band edge length (mm).
    pub band_edge_max: f64,
    /// Number of band triangles.
    pub band_faces: usize,
    /// IOS crown vertices kept: all of them except the ones trimmed from the margin fringe
    /// (`ios_vertices_trimmed`) and the ones the crown repair dropped (`ios_vertices_dropped`).
    pub crown_vertices: usize,
    /// Small crown holes filled.
    pub holes_filled: usize,
    /// IOS crown vertices trimmed from the margin fringe (folded over other crown faces, or
    /// crossed by the band; all within the fringe reach of the original margin).
    pub ios_vertices_trimmed: usize,
    /// Largest geodesic distance (mm) from the original margin of a trimmed IOS vertex (0 when
    /// none was trimmed).
    pub ios_trim_reach_mm: f64,
    /// IOS crown vertices the crown repair dropped: stray tooth-labelled islands apart from the
    /// crown (a segmentation tool's label noise, given back to the gingiva) and vertices in no
    /// face (0 on a clean crown).
    pub ios_vertices_dropped: usize,
    /// CBCT faces removed by the crown cut.
    pub cbct_faces_removed: usize,
    /// Intersecting face pairs with a band face that the band rebuilds and the untangling left
    /// (exact test; 0 when the band adds no crossing, or when the untangling is off).
    pub band_crossings_left: usize,
    /// Intersecting face pairs of two crown faces, at least one of them added to the crown (a
    /// hole's cap, a slit's strip; exact test). Caps and strips are made clear of the crown,
    /// so this is 0 unless a hole's rim left no cap clear (a warning says so).
    pub crown_crossings_added: usize,
}

impl ToothQuality {
    /// Watertight: closed, manifold, one component, positive volume, nothing degenerate, no
    /// self-intersection (when checked).
    pub fn watertight(&self) -> bool {
        self.closed
            && self.manifold
            && self.components == 1
            && self.volume > 0.0
            && self.degenerate_faces == 0
            && self.self_intersections.unwrap_or(0) == 0
    }

    /// Intersecting face pairs the fusion added and left: those with a band face and those with
    /// a face added to the crown (0 when the output contract's no-crossing part holds).
    pub fn crossings_added(&self) -> usize {
        self.band_crossings_left + self.crown_crossings_added
    }
}

/// Angles (degrees) of a triangle.
pub fn triangle_angles(a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> [f64; 3] {
    let ang =
        |p: glam::DVec3, q: glam::DVec3, r: glam::DVec3| (q - p).angle_between(r - p).to_degrees();
    [ang(a, b, c), ang(b, c, a), ang(c, a, b)]
}

/// Measures `mesh`; `band` lists the band's face indices.
pub fn measure(
    mesh: &TriMesh,
    band: std::ops::Range<usize>,
    check_self_intersections: bool,
) -> ToothQuality {
    let r = mesh.topology_report();
    let mut q = ToothQuality {
        closed: r.boundary_edges == 0,
        manifold: r.non_manifold_edges == 0 && r.non_manifold_vertices == 0,
        boundary_edges: r.boundary_edges,
        non_manifold_edges: r.non_manifold_edges,
        non_manifold_vertices: r.non_manifold_vertices,
        components: r.components,
        volume: mesh.signed_volume(),
        degenerate_faces: mesh_check::degenerate_faces(mesh),
        self_intersections: check_self_intersections
            .then(|| mesh_check::self_intersections(mesh).len()),
        band_min_angle_deg: 180.0,
        band_edge_min: f64::INFINITY,
        band_faces: band.len(),
        ..Default::default()
    };
    let mut sum = 0.0;
    for f in band.clone() {
        let [a, b, c] = mesh.corners(f);
        for ang in triangle_angles(a, b, c) {
            q.band_min_angle_deg = q.band_min_angle_deg.min(ang);
        }
        for l in [(b - a).length(), (c - b).length(), (a - c).length()] {
            q.band_edge_min = q.band_edge_min.min(l);
            q.band_edge_max = q.band_edge_max.max(l);
            sum += l;
        }
    }
    q.band_edge_mean = if band.is_empty() {
        0.0
    } else {
        sum / (3 * band.len()) as f64
    };
    q
}
