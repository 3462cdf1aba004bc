//! Collapsing a margin vertex onto a neighbour, on small hand-made crowns.

use super::*;
use glam::DVec3;

/// A crown patch in the xy-plane, counter-clockwise seen from +z: margin vertices `i` = 0,
/// `k` = 1 (at height `k_y` above the line from `i` to `j`) and `j` = 2, interior `a` = 3,
/// `b` = 4, and `c` = 5 on the far side. Margin loop: 0 → 1 → 2 → 4 → 5 → 3.
fn patch(k_y: f64) -> TriMesh {
    TriMesh::new(
        vec![
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, k_y, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ],
        vec![[0, 1, 3], [1, 4, 3], [1, 2, 4], [3, 4, 5]],
    )
}

#[test]
fn a_collapsed_margin_vertex_leaves_the_margin_along_the_chord() {
    for k_y in [0.0, 1e-6, -1e-3, 0.2] {
        let m = patch(k_y);
        let c = collapse(&m, 1, 0).expect("collapses onto 0");
        // The face on the margin edge 0-1 goes; the others hold 0 where they held 1.
        assert_eq!(
            c.triangles,
            vec![[0, 4, 3], [0, 2, 4], [3, 4, 5]],
            "k_y {k_y}"
        );
        assert_eq!(c.positions, m.positions);
        let loops = boundary_loops(&c);
        assert_eq!(loops, vec![vec![0, 2, 4, 5, 3]], "k_y {k_y}");
        let topo = EdgeTopology::new(&c);
        assert_eq!(topo.edge_counts(), (5, 0));
        // Onto the other neighbour: the face on the edge 1-2 goes.
        let c = collapse(&m, 1, 2).expect("collapses onto 2");
        assert_eq!(
            c.triangles,
            vec![[0, 2, 3], [2, 4, 3], [3, 4, 5]],
            "k_y {k_y}"
        );
        assert_eq!(boundary_loops(&c), vec![vec![0, 2, 4, 5, 3]], "k_y {k_y}");
    }
}

#[test]
fn a_collapse_is_refused_off_an_edge_or_when_it_would_turn_a_face_over_or_cross_the_crown() {
    // Not an edge of the crown.
    assert!(collapse(&patch(0.0), 1, 5).is_none());
    // A margin vertex far above its neighbours' line: collapsing it onto 0 turns the face
    // (1, 2, 4) over.
    let mut m = patch(0.0);
    m.positions[1] = DVec3::new(1.5, 1.5, 0.0);
    m.triangles = vec![[0, 1, 3], [1, 4, 3], [2, 4, 1], [3, 4, 5]];
    assert!(collapse(&m, 1, 0).is_none());
    // A fin through the notch below a margin vertex that juts into the crown: the faces
    // re-made over the notch would cross it.
    let mut m = patch(0.3);
    let f = m.positions.len() as u32;
    m.positions.extend([
        DVec3::new(0.0, 0.1, -1.0),
        DVec3::new(0.05, 0.1, 1.0),
        DVec3::new(-0.05, 0.1, 1.0),
    ]);
    m.triangles.push([f, f + 1, f + 2]);
    assert!(
        crossing_pairs(&m, &[4]).is_empty(),
        "the fin crosses no crown face"
    );
    assert!(collapse(&m, 1, 0).is_none());
    assert!(collapse(&m, 1, 2).is_none());
    // Without the fin both collapses are made.
    assert!(collapse(&patch(0.3), 1, 0).is_some() && collapse(&patch(0.3), 1, 2).is_some());
}
