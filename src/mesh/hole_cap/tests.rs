use super::*;

/// A flat `n` x `n` grid of unit squares in z = 0 (counter-clockwise seen from +z) with the
/// squares whose lower-left corner is in `holes` left out. Returns the mesh and the rim of
/// the hole (the boundary loop through the hole's vertices, surface on its left).
fn grid_with_hole(n: usize, holes: &[(usize, usize)]) -> (TriMesh, Vec<u32>) {
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(DVec3::new(i as f64, j as f64, 0.0));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if holes.contains(&(i, j)) {
                continue;
            }
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let m = TriMesh::new(positions, triangles);
    let loops = crate::mesh::boundary_loops(&m);
    // The hole's rim: the loop not through the grid's corner vertex 0.
    let rim = loops.into_iter().find(|l| !l.contains(&0)).expect("a hole");
    (m, rim)
}

/// Adds a separate triangle (vertices appended) to `m`.
fn add_triangle(m: &mut TriMesh, p: [DVec3; 3]) {
    let b = m.positions.len() as u32;
    m.positions.extend(p);
    m.triangles.push([b, b + 1, b + 2]);
}

/// Face pairs the mesh crosses once `cap` is added.
fn crossings_with(m: &TriMesh, cap: &Cap) -> usize {
    let mut m = m.clone();
    let grid = TriangleGrid::new(&m, 0.0);
    crossings_of(&mut m, &grid, cap).0
}

/// [`cap_hole`] of `rim` on `m` as a repair calls it.
fn capped(m: &mut TriMesh, rim: &[u32]) -> Cap {
    let topo = EdgeTopology::new(m);
    let grid = TriangleGrid::new(m, 0.0);
    cap_hole(
        m,
        &Surface {
            topo: &topo,
            grid: &grid,
        },
        rim,
    )
}

#[test]
fn a_flat_hole_gets_the_fan_from_its_centroid() {
    let (mut m, rim) = grid_with_hole(4, &[(1, 1), (2, 1), (1, 2), (2, 2)]);
    let cap = capped(&mut m, &rim);
    assert_eq!(cap.apex, Some(DVec3::new(2.0, 2.0, 0.0)));
    assert_eq!(cap.faces.len(), rim.len());
    assert_eq!(cap.crossings, 0);
    // The cap closes the hole: every rim edge is used reversed by one cap face.
    for j in 0..rim.len() {
        let (a, b) = (rim[j], rim[(j + 1) % rim.len()]);
        let uses = cap
            .faces
            .iter()
            .filter(|t| (0..3).any(|k| t[k] == b && t[(k + 1) % 3] == a))
            .count();
        assert_eq!(uses, 1, "rim edge {a}-{b}");
    }
}

#[test]
fn a_fin_over_the_hole_is_cleared_by_raising_the_apex() {
    let (mut m, rim) = grid_with_hole(4, &[(1, 1), (2, 1), (1, 2), (2, 2)]);
    // A small upright fin at the hole's centre, reaching 0.2 above and below its plane.
    add_triangle(
        &mut m,
        [
            DVec3::new(1.8, 2.0, -0.2),
            DVec3::new(2.2, 2.0, -0.2),
            DVec3::new(2.0, 2.0, 0.2),
        ],
    );
    let centroid = DVec3::new(2.0, 2.0, 0.0);
    let apex_index = m.positions.len() as u32;
    let centroid_fan = fan(&rim, apex_index, centroid);
    assert!(
        crossings_with(&m, &centroid_fan) > 0,
        "the centroid's fan crosses the fin"
    );
    let cap = capped(&mut m, &rim);
    assert_eq!(cap.crossings, 0);
    assert_eq!(crossings_with(&m, &cap), 0);
    let apex = cap.apex.expect("a fan");
    assert_eq!(
        (apex.x, apex.y),
        (2.0, 2.0),
        "moved along the rim's normal only"
    );
    assert!(
        apex.z.abs() > 0.2,
        "{apex}: raised or lowered clear of the fin"
    );
    assert_eq!(m.triangles.len(), 25, "the surface is left as it was");
}

#[test]
fn a_hole_no_fan_can_clear_gets_a_cap_on_its_rim() {
    // An L-shaped hole: its rim's centroid lies over the surface beside the inner corner.
    let (mut m, rim) = grid_with_hole(5, &[(1, 1), (2, 1), (3, 1), (1, 2), (1, 3)]);
    let c = rim
        .iter()
        .fold(DVec3::ZERO, |a, &v| a + m.positions[v as usize])
        / rim.len() as f64;
    assert!(
        c.x > 2.0 && c.y > 2.0,
        "the centroid {c} lies outside the hole"
    );
    // An upright post through the centroid, reaching past every apex tried: every fan's apex
    // lies in it.
    add_triangle(
        &mut m,
        [
            c + DVec3::new(0.0, -0.1, -9.0),
            c + DVec3::new(0.0, 0.1, -9.0),
            c + DVec3::new(0.0, 0.0, 9.0),
        ],
    );
    let cap = capped(&mut m, &rim);
    assert_eq!(cap.crossings, 0);
    assert_eq!(crossings_with(&m, &cap), 0);
    assert_eq!(cap.apex, None, "a cap on the rim's own vertices");
    assert_eq!(cap.faces.len(), rim.len() - 2);
    // It lies in the hole's plane, each face oriented as the surface (+z).
    for t in &cap.faces {
        let [a, b, d] = t.map(|v| m.positions[v as usize]);
        assert_eq!(a.z.max(b.z).max(d.z), 0.0);
        assert!((b - a).cross(d - a).z > 0.0, "{t:?}");
    }
}

#[test]
fn a_hole_no_cap_can_clear_keeps_the_cap_crossing_least_and_counts_it() {
    let (mut m, rim) = grid_with_hole(4, &[(1, 1), (2, 1), (1, 2), (2, 2)]);
    // A wall through the whole hole, far above and below it: every cap crosses it.
    add_triangle(
        &mut m,
        [
            DVec3::new(-5.0, 2.0, -50.0),
            DVec3::new(9.0, 2.0, -50.0),
            DVec3::new(2.0, 2.0, 50.0),
        ],
    );
    let cap = capped(&mut m, &rim);
    assert!(cap.crossings > 0);
    assert_eq!(crossings_with(&m, &cap), cap.crossings);
}

#[test]
fn a_chord_that_is_already_an_edge_is_not_used() {
    // A triangle-free square hole whose diagonal chords both exist elsewhere in the mesh: no
    // triangulation on the rim is possible, so the cap is a fan.
    let (mut m, rim) = grid_with_hole(3, &[(1, 1)]);
    assert_eq!(rim.len(), 4);
    m.triangles.push([rim[0], rim[2], 0]);
    m.triangles.push([rim[1], rim[3], 0]);
    let topo = EdgeTopology::new(&m);
    for shape in [Shape::Tilt, Shape::Fold] {
        assert_eq!(flat_cap(&m, &topo, &rim, shape), None);
    }
}
