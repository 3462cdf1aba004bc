use super::*;
use crate::mesh::fixtures::ellipsoid;
use crate::mesh::{RepairOptions, RepairReport, repair_open_surface, repair_taken};

/// A wavy square grid of `k` x `k` cells, each split in two along alternating diagonals: an open
/// disk the repair leaves as it is.
fn grid(k: u32) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            let (x, y) = (i as f64 * 0.3, j as f64 * 0.3);
            positions.push(DVec3::new(x, y, 0.05 * (3.0 * x).sin() * (2.0 * y).cos()));
        }
    }
    let id = |i: u32, j: u32| j * (k + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..k {
        for i in 0..k {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.extend([[a, b, c], [a, c, d]]);
            } else {
                triangles.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    TriMesh::new(positions, triangles)
}

/// An open cap: the ellipsoid's faces above its equator (a disk whose boundary is a ring).
fn cap() -> TriMesh {
    let e = ellipsoid(12, 24, 5.0, 4.0);
    let t = e
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&v| e.positions[v as usize].z > -0.5))
        .collect();
    let mut m = TriMesh::new(e.positions, t);
    m.compact();
    m
}

/// Deterministic pseudo-random removal masks of `mesh`: faces at random (holes, islands, pinches
/// anywhere), faces touching the boundary (what the fringe trim peels, often pinching), and
/// single faces on a boundary edge (a peel that only shortens the margin, or pinches it where the
/// face's third corner lies on the boundary too).
fn masks(mesh: &TriMesh, count: usize) -> Vec<Vec<bool>> {
    let topo = EdgeTopology::new(mesh);
    let on_edge = topo.on_single_face_edge(mesh.positions.len());
    let margin_faces: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&f| {
            let t = mesh.triangles[f];
            (0..3).any(|k| topo.edge_face_count(t[k], t[(k + 1) % 3]) == 1)
        })
        .collect();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    (0..count)
        .map(|k| match k % 3 {
            2 => {
                let mut m = vec![false; mesh.triangles.len()];
                m[margin_faces[next() as usize % margin_faces.len()]] = true;
                m
            }
            _ => {
                let rate = [3, 10, 40][k % 3 + (k / 3) % 2];
                mesh.triangles
                    .iter()
                    .map(|t| {
                        let boundary = t.iter().any(|&v| on_edge[v as usize]);
                        let pick = next() % 100 < rate;
                        if k % 3 == 0 { pick } else { boundary && pick }
                    })
                    .collect()
            }
        })
        .collect()
}

fn repaired_without_filling(mesh: &TriMesh) -> (TriMesh, Vec<u32>, RepairReport) {
    repair_open_surface(
        mesh,
        &RepairOptions {
            max_hole_fraction: 0.0,
        },
    )
}

#[test]
fn the_topology_less_some_faces_is_the_one_built_anew() {
    for mesh in [grid(12), cap()] {
        let topo = EdgeTopology::new(&mesh);
        for remove in masks(&mesh, 30) {
            let cut = without_faces(&mesh, &remove);
            let fresh = EdgeTopology::new(&cut);
            let derived = topo.without_faces(&remove);
            assert_eq!(derived.half_edges, fresh.half_edges);
            for v in 0..mesh.positions.len() as u32 + 2 {
                assert_eq!(derived.leaving(v), fresh.leaving(v), "vertex {v}");
            }
        }
    }
}

#[test]
fn surfaces_the_repair_leaves_as_they_are_pass_and_others_fail() {
    for mesh in [grid(6), cap()] {
        let topo = EdgeTopology::new(&mesh);
        assert!(is_repaired(&mesh, &topo));
        let (rep, src, report) = repaired_without_filling(&mesh);
        assert!(report.is_clean());
        assert_eq!(rep.triangles, mesh.triangles);
        assert_eq!(src, (0..mesh.positions.len() as u32).collect::<Vec<_>>());
    }
    let g = grid(6);
    let mut bad: Vec<(&str, TriMesh)> = Vec::new();
    let mut twice = g.clone();
    twice.triangles.push(g.triangles[7]);
    bad.push(("a face twice", twice));
    let mut turned = g.clone();
    turned.triangles[7].swap(1, 2);
    bad.push(("a face turned", turned));
    let mut flat = g.clone();
    flat.positions[g.triangles[7][0] as usize] = g.positions[g.triangles[7][1] as usize];
    bad.push(("a face of no area", flat));
    let mut island = g.clone();
    let n = island.positions.len() as u32;
    island
        .positions
        .extend([DVec3::new(9.0, 0.0, 0.0), DVec3::new(9.0, 1.0, 0.0)]);
    island.positions.push(DVec3::new(10.0, 0.0, 0.0));
    island.triangles.push([n, n + 2, n + 1]);
    bad.push(("an island", island));
    // A face off the grid whose removal leaves one of its corners with two fans, the grid still
    // one piece: a bow-tie there.
    let bow = (0..g.triangles.len())
        .map(|f| {
            let mut m = g.clone();
            m.triangles.remove(f);
            m
        })
        .find(|m| {
            !crate::mesh::non_manifold_vertices(m).is_empty()
                && crate::mesh::connected_components(m).1 == 1
        })
        .expect("a face whose removal pinches the grid");
    bad.push(("a bow-tie", bow));
    // Two faces on the same corners, turned against each other, alone.
    let pillow = TriMesh::new(g.positions.clone(), vec![[0, 1, 8], [0, 8, 1]]);
    bad.push(("a face twice the other way round", pillow));
    for (what, mesh) in bad {
        let topo = EdgeTopology::new(&mesh);
        assert!(!is_repaired(&mesh, &topo), "{what}");
        let (rep, _, report) = repaired_without_filling(&mesh);
        let mut compact = mesh.clone();
        compact.compact();
        assert!(
            !report.is_clean() || rep != compact,
            "{what}: the repair changes it"
        );
    }
}

#[test]
fn a_removal_taken_away_is_what_the_repair_returns() {
    let (mut answered, mut declined) = (0, 0);
    for mesh in [grid(12), cap()] {
        let topo = EdgeTopology::new(&mesh);
        assert!(is_repaired(&mesh, &topo));
        for remove in masks(&mesh, 60) {
            let cut = without_faces(&mesh, &remove);
            let expect = repaired_without_filling(&cut);
            assert_eq!(repair_taken(&mesh, &topo, &remove), expect);
            match taken_away(&mesh, &topo, &remove) {
                Some(t) => {
                    answered += 1;
                    assert!(expect.2.is_clean());
                    assert_eq!((&t.mesh, &t.source), (&expect.0, &expect.1));
                    assert_eq!(t.topo.half_edges, EdgeTopology::new(&t.mesh).half_edges);
                    assert_eq!(t.loops, boundary_loops_of(&t.topo));
                    assert_eq!(t.loops.len(), 1);
                    // What it gives is again a surface the repair leaves as it is.
                    assert!(is_repaired(&t.mesh, &t.topo) || t.mesh.triangles.len() < 3);
                }
                None => declined += 1,
            }
        }
    }
    // Both answers occur: removals that pinch, cut pieces off or open holes, and removals
    // that only shorten the margin.
    assert!(answered >= 10 && declined >= 10, "{answered} / {declined}");
}
