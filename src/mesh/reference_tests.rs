//! Randomised equivalence tests: the optimised topology routines against the plain reference
//! implementations they replaced (same results on arbitrary, also broken, meshes).

use super::TriMesh;
use super::topology::{EdgeTopology, boundary_loops_of, connected_components_of};
use super::validate::{ValidationReport, non_manifold_vertices};
use glam::DVec3;
use std::collections::BTreeMap;

/// The plain per-vertex fan union (reference for [`non_manifold_vertices`]).
pub(super) fn reference_non_manifold_vertices(mesh: &TriMesh) -> Vec<u32> {
    let n = mesh.positions.len();
    // Corners grouped by vertex (counting sort; faces in order within a vertex):
    // (vertex, face, the two other vertices).
    let mut start = vec![0usize; n + 1];
    for t in &mesh.triangles {
        for &v in t {
            if (v as usize) < n {
                start[v as usize + 1] += 1;
            }
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut corners: Vec<(u32, u32, u32, u32)> = vec![(0, 0, 0, 0); start[n]];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let v = t[k] as usize;
            if v < n {
                corners[start[v]] = (t[k], f as u32, t[(k + 1) % 3], t[(k + 2) % 3]);
                start[v] += 1;
            }
        }
    }
    let mut out = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut nb: Vec<(u32, usize)> = Vec::new();
    let mut i = 0;
    while i < corners.len() {
        let v = corners[i].0;
        let mut j = i;
        while j < corners.len() && corners[j].0 == v {
            j += 1;
        }
        let fan = &corners[i..j];
        // Union faces of the fan that share a neighbour vertex (= share an edge through v).
        let m = fan.len();
        parent.clear();
        parent.extend(0..m);
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        nb.clear();
        for (idx, c) in fan.iter().enumerate() {
            nb.push((c.2, idx));
            nb.push((c.3, idx));
        }
        nb.sort_unstable();
        for w in nb.windows(2) {
            if w[0].0 == w[1].0 {
                let (a, b) = (find(&mut parent, w[0].1), find(&mut parent, w[1].1));
                parent[a.max(b)] = a.min(b);
            }
        }
        let roots = (0..m).filter(|&x| find(&mut parent, x) == x).count();
        if roots > 1 {
            out.push(v);
        }
        i = j;
    }
    out
}

/// The report built from the sorted undirected edge list (reference for
/// [`TriMesh::topology_report`]).
pub(super) fn reference_report(mesh: &TriMesh) -> ValidationReport {
    let topo = EdgeTopology::new(mesh);
    let mut boundary_edges = 0;
    let mut non_manifold_edges = 0;
    for (a, b, c) in topo.undirected_edges() {
        let same_dir =
            topo.faces_of_directed(a, b).count() > 1 || topo.faces_of_directed(b, a).count() > 1;
        if c == 1 {
            boundary_edges += 1;
        } else if c > 2 || same_dir {
            non_manifold_edges += 1;
        }
    }
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
    }
    let (_, components) = connected_components_of(&topo, mesh.triangles.len());
    let loops = if non_manifold_edges == 0 {
        boundary_loops_of(&topo).len()
    } else {
        0
    };
    ValidationReport {
        vertices: mesh.positions.len(),
        faces: mesh.triangles.len(),
        boundary_edges,
        non_manifold_edges,
        non_manifold_vertices: reference_non_manifold_vertices(mesh).len(),
        unused_vertices: used.iter().filter(|u| !**u).count(),
        components,
        boundary_loops: loops,
    }
}

/// A deterministic pseudo-random generator (64-bit LCG).
pub(super) struct Lcg(pub(super) u64);

impl Lcg {
    pub(super) fn below(&mut self, n: u32) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as u32
    }
}

/// A closed `w × h` torus grid, then damaged by `rng`: faces removed, flipped, duplicated,
/// collapsed, vertices glued (bow-ties, non-manifold edges), out-of-range corners; `kinds` = 2
/// only removes faces, 8 does everything.
pub(super) fn damaged_torus(rng: &mut Lcg, w: u32, h: u32, damage: u32, kinds: u32) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (u, v) = (
                i as f64 / w as f64 * std::f64::consts::TAU,
                j as f64 / h as f64 * std::f64::consts::TAU,
            );
            let r = 3.0 + v.cos();
            positions.push(DVec3::new(r * u.cos(), r * u.sin(), v.sin()));
        }
    }
    let id = |i: u32, j: u32| (j % h) * w + (i % w);
    let mut triangles = Vec::new();
    for j in 0..h {
        for i in 0..w {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let nv = positions.len() as u32;
    for _ in 0..damage {
        let nf = triangles.len() as u32;
        if nf == 0 {
            break;
        }
        let f = rng.below(nf) as usize;
        match rng.below(kinds) {
            0 | 1 => {
                triangles.remove(f);
            }
            2 => triangles[f].swap(1, 2),
            3 => triangles.push(triangles[f]),
            4 => triangles[f][rng.below(3) as usize] = rng.below(nv),
            5 => {
                let k = rng.below(3) as usize;
                triangles[f][k] = triangles[f][(k + 1) % 3];
            }
            6 => {
                let g = rng.below(nf) as usize;
                triangles.push([triangles[f][0], triangles[f][1], triangles[g][2]]);
            }
            _ => triangles.push([rng.below(nv), rng.below(nv), rng.below(nv + 2)]),
        }
    }
    TriMesh::new(positions, triangles)
}

#[test]
fn fan_test_and_report_match_the_reference() {
    let mut rng = Lcg(7);
    for case in 0..400u32 {
        let (w, h) = (3 + rng.below(9), 3 + rng.below(9));
        let kinds = if case % 2 == 0 { 2 } else { 8 };
        let m = damaged_torus(&mut rng, w, h, case % 40, kinds);
        assert_eq!(
            non_manifold_vertices(&m),
            reference_non_manifold_vertices(&m),
            "case {case}"
        );
        assert_eq!(m.topology_report(), reference_report(&m), "case {case}");
    }
}

/// Splitting with a map per label, looked up per face (reference for the label split).
pub(super) fn reference_split_faces(
    mesh: &TriMesh,
    face_labels: &[Option<i32>],
) -> BTreeMap<i32, super::SubMesh> {
    let mut out: BTreeMap<i32, super::SubMesh> = BTreeMap::new();
    // Per label: input vertex → local index, built lazily in face order (deterministic).
    let mut local: BTreeMap<i32, Vec<u32>> = BTreeMap::new();
    for (f, (t, l)) in mesh.triangles.iter().zip(face_labels).enumerate() {
        let Some(l) = *l else { continue };
        let sub = out.entry(l).or_insert_with(|| super::SubMesh {
            label: l,
            mesh: TriMesh::default(),
            source_vertex: Vec::new(),
            source_face: Vec::new(),
        });
        let map = local
            .entry(l)
            .or_insert_with(|| vec![u32::MAX; mesh.positions.len()]);
        let mut tri = [0u32; 3];
        for (k, &v) in t.iter().enumerate() {
            if map[v as usize] == u32::MAX {
                map[v as usize] = sub.mesh.positions.len() as u32;
                sub.mesh.positions.push(mesh.positions[v as usize]);
                sub.source_vertex.push(v);
            }
            tri[k] = map[v as usize];
        }
        sub.mesh.triangles.push(tri);
        sub.source_face.push(f as u32);
    }
    out
}

#[test]
fn label_split_matches_the_reference() {
    let mut rng = Lcg(3);
    for case in 0..200u32 {
        let (w, h) = (3 + rng.below(10), 3 + rng.below(10));
        let m = damaged_torus(&mut rng, w, h, case % 10, 2);
        // Face labels in runs (as teeth are) or scattered; vertex labels leave straddling faces
        // unlabeled.
        let run = 1 + rng.below(40);
        let labels: Vec<i32> = (0..m.triangles.len() as u32)
            .map(|f| {
                if case % 3 == 0 {
                    rng.below(5) as i32 - 1
                } else {
                    ((f / run) % 7) as i32 * 10 - 20
                }
            })
            .collect();
        let got = super::split_by_face_labels(&m, &labels).unwrap();
        let all: Vec<Option<i32>> = labels.iter().map(|&l| Some(l)).collect();
        assert_eq!(got, reference_split_faces(&m, &all), "case {case}");
        let vl: Vec<i32> = (0..m.positions.len() as u32)
            .map(|v| (v / run % 3) as i32)
            .collect();
        let fl: Vec<Option<i32>> = m
            .triangles
            .iter()
            .map(|t| {
                let l = vl[t[0] as usize];
                (vl[t[1] as usize] == l && vl[t[2] as usize] == l).then_some(l)
            })
            .collect();
        assert_eq!(
            super::split_by_vertex_labels(&m, &vl).unwrap(),
            reference_split_faces(&m, &fl),
            "case {case}"
        );
    }
}

#[test]
fn validation_keeping_the_topology_fails_alike() {
    let mut rng = Lcg(11);
    for case in 0..300u32 {
        let kinds = if case % 2 == 0 { 2 } else { 8 };
        let (w, h) = (3 + rng.below(6), 3 + rng.below(6));
        let m = damaged_torus(&mut rng, w, h, case % 12, kinds);
        for require_closed in [false, true] {
            let o = super::ValidateOptions {
                require_closed,
                allow_zero_area: case % 3 == 0,
            };
            assert_eq!(
                m.validate(&o).map(|_| ()),
                m.validate_into_topology(&o).map(|_| ()),
                "case {case}"
            );
        }
    }
}

#[test]
fn duplicate_face_found_as_by_a_full_sort() {
    let mut rng = Lcg(21);
    for case in 0..200u32 {
        let (w, h) = (3 + rng.below(8), 3 + rng.below(8));
        let mut m = damaged_torus(&mut rng, w, h, case % 5, 2);
        for _ in 0..case % 4 {
            let f = rng.below(m.triangles.len() as u32) as usize;
            let mut t = m.triangles[f];
            t.rotate_left(rng.below(3) as usize);
            if rng.below(2) == 0 {
                t.swap(0, 1);
            }
            let at = rng.below(m.triangles.len() as u32 + 1) as usize;
            m.triangles.insert(at, t);
        }
        let mut keyed: Vec<([u32; 3], usize)> = m
            .triangles
            .iter()
            .enumerate()
            .map(|(f, t)| {
                let mut k = *t;
                k.sort_unstable();
                (k, f)
            })
            .collect();
        keyed.sort_unstable();
        let expect =
            keyed
                .windows(2)
                .find(|w| w[0].0 == w[1].0)
                .map(|w| crate::Error::DuplicateFace {
                    face: w[1].1,
                    first: w[0].1,
                });
        let got = m
            .validate(&super::ValidateOptions::default())
            .err()
            .filter(|e| matches!(e, crate::Error::DuplicateFace { .. }));
        assert_eq!(got, expect, "case {case}");
    }
}
