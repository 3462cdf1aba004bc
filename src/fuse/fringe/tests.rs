//! Unit tests of the `fringe` module.

use super::*;
use crate::mesh::{RepairOptions, boundary_loops, repair_open_surface};
use crate::mesh_check::triangles_intersect;
use glam::DVec3;

/// A fan of 8 faces: apex 0 at (0, 0, 1) over the unit ring 1..=8 (its margin).
fn fan_crown() -> TriMesh {
    let mut positions = vec![DVec3::new(0.0, 0.0, 1.0)];
    positions.extend((0..8).map(|k| {
        let a = std::f64::consts::TAU * k as f64 / 8.0;
        DVec3::new(a.cos(), a.sin(), 0.0)
    }));
    let triangles: Vec<[u32; 3]> = (0..8u32).map(|k| [0, 1 + k, 1 + (k + 1) % 8]).collect();
    TriMesh::new(positions, triangles)
}

/// A fan crown: apex 0 at 1 mm from its margin (the ring 1..=8). A listed face on a
/// margin edge goes only with [`Listed::Apex`], and then alone: its apex stays in the faces
/// around, so no vertex is lost and the crown stays one disk.
#[test]
fn a_listed_margin_face_goes_with_its_apex_beyond_the_reach_kept() {
    let crown = fan_crown();
    let src: Vec<u32> = (0..9).collect();
    let dist_in = edge_distance(&crown, &(1..=8).collect::<Vec<u32>>(), 10.0);
    assert!(dist_in[0] > 0.3 && dist_in[1..].iter().all(|&d| d == 0.0));
    assert!(trim_fringe(&crown, &src, &dist_in, 0.3, &[2], Listed::Within).is_none());
    let (trimmed, map, t) = trim_fringe(&crown, &src, &dist_in, 0.3, &[2], Listed::Apex).unwrap();
    assert_eq!((t.faces, t.vertices), (1, 0), "{t:?}");
    assert_eq!(trimmed.triangles.len(), 7);
    assert_eq!(map.len(), 9);
    assert_eq!(boundary_loops(&trimmed).len(), 1);
    // The apex is now on the margin, at its position.
    let apex = map.iter().position(|&s| s == 0).unwrap();
    assert_eq!(trimmed.positions[apex], crown.positions[0]);
}

/// The fan crown of the test above with its margin moved beyond the reach (every input
/// vertex 0.5 mm or more from the original margin, as after earlier trims): a listed face on
/// a margin edge goes only with [`Listed::MarginEdge`], alone, and no vertex is lost.
#[test]
fn a_listed_margin_face_goes_where_the_margin_lies_beyond_the_reach() {
    let crown = fan_crown();
    let src: Vec<u32> = (0..9).collect();
    let mut dist_in = vec![0.5; 9];
    dist_in[0] = 1.5;
    for mode in [Listed::Within, Listed::Apex] {
        assert!(trim_fringe(&crown, &src, &dist_in, 0.3, &[2], mode).is_none());
    }
    let (trimmed, map, t) =
        trim_fringe(&crown, &src, &dist_in, 0.3, &[2], Listed::MarginEdge).unwrap();
    assert_eq!((t.faces, t.vertices), (1, 0), "{t:?}");
    assert_eq!(trimmed.triangles.len(), 7);
    assert_eq!(boundary_loops(&trimmed).len(), 1);
    for s in 0..9u32 {
        let v = map.iter().position(|&x| x == s).unwrap();
        assert_eq!(trimmed.positions[v], crown.positions[s as usize]);
    }
    // An unlisted face is not taken.
    assert!(trim_fringe(&crown, &src, &dist_in, 0.3, &[], Listed::MarginEdge).is_none());
}

/// A disk of two rings round an apex (apex 0, ring 1..=8 at 0.5 mm, margin 9..=16 at
/// 1 mm) with a tab face on the margin edge (9, 10) holding vertex 17; faces 0..8 the
/// apex fan, then the annulus, then the tab.
fn ringed_disk() -> TriMesh {
    let mut positions = vec![DVec3::ZERO];
    for r in [0.5, 1.0] {
        positions.extend((0..8).map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 8.0;
            DVec3::new(r * a.cos(), r * a.sin(), 0.0)
        }));
    }
    positions.push(DVec3::new(1.3, 0.5, 0.0));
    let mut triangles: Vec<[u32; 3]> = (0..8u32).map(|k| [0, 1 + k, 1 + (k + 1) % 8]).collect();
    for k in 0..8u32 {
        let (a, b) = (1 + k, 1 + (k + 1) % 8);
        let (c, d) = (9 + k, 9 + (k + 1) % 8);
        triangles.push([a, c, d]);
        triangles.push([a, d, b]);
    }
    triangles.push([10, 9, 17]);
    TriMesh::new(positions, triangles)
}

/// A removal that would cut the crown apart, or punch a hole into it, is put back while
/// the rest of the round goes: removing the annulus face under the tab drops the tab's
/// vertex beyond the reach, and removing an apex face opens a second loop; both faces are
/// kept and the harmless margin face elsewhere goes.
#[test]
fn a_removal_that_pinches_is_put_back_and_the_rest_goes() {
    let crown = ringed_disk();
    let map: Vec<u32> = (0..18).collect();
    // The tab's vertex stands for crown beyond the reach that hangs on the removed face.
    let mut dist_in = vec![0.0; 18];
    dist_in[17] = 5.0;
    let under_tab = crown
        .triangles
        .iter()
        .position(|t| t.contains(&9) && t.contains(&10) && !t.contains(&17))
        .unwrap();
    let harmless = crown
        .triangles
        .iter()
        .position(|t| t.contains(&13) && t.contains(&14))
        .unwrap();
    // With the whole crown repaired after the removal, and with only what the removal changed
    // (the ringed disk is a surface the repair leaves as it is).
    let topo = EdgeTopology::new(&crown);
    assert!(is_repaired(&crown, &topo));
    for repaired in [None, Some(&topo)] {
        let mut remove = vec![false; crown.triangles.len()];
        for f in [0, under_tab, harmless] {
            remove[f] = true;
        }
        let Peeled {
            crown: rep,
            map: next,
            removed,
            face_of,
            topo: rep_topo,
            repaired: known,
        } = peel(&crown, &map, &mut remove, &dist_in, 0.3, repaired).unwrap();
        assert_eq!(removed, 1);
        assert_eq!(known, repaired.is_some());
        assert_eq!(rep_topo.half_edges, EdgeTopology::new(&rep).half_edges);
        // Only the harmless face went: every other face kept, in order.
        let others: Vec<u32> = (0..crown.triangles.len() as u32)
            .filter(|&f| f as usize != harmless)
            .collect();
        assert_eq!(face_of, Some(others));
        assert!(remove[harmless] && !remove[0] && !remove[under_tab]);
        assert_eq!(rep.triangles.len(), crown.triangles.len() - 1);
        assert_eq!(boundary_loops(&rep).len(), 1);
        assert!(next.contains(&17));
        // Alone, each of the two is refused.
        for f in [0, under_tab] {
            let mut only = vec![false; crown.triangles.len()];
            only[f] = true;
            assert!(
                peel(&crown, &map, &mut only, &dist_in, 0.3, repaired).is_none(),
                "face {f}"
            );
        }
    }
}

/// A flat fan crown folded at the margin (vertex 2 swung past vertex 3, so the faces on
/// either side of the edge 0–2 overlap) whose apex is no input vertex (a filled hole's):
/// both folded faces are listed, the apex has no distance from the margin, and the trim
/// neither fails on it nor loses it; one of the two faces goes and the crown stays a disk.
#[test]
fn a_fold_at_a_vertex_that_is_no_input_vertex_is_trimmed() {
    let mut positions = vec![DVec3::ZERO];
    positions.extend((0..8).map(|k| {
        let deg = if k == 1 { 100.0f64 } else { 45.0 * k as f64 };
        let a = deg.to_radians();
        DVec3::new(a.cos(), a.sin(), 0.0)
    }));
    let triangles: Vec<[u32; 3]> = (0..8u32).map(|k| [0, 1 + k, 1 + (k + 1) % 8]).collect();
    let crown = TriMesh::new(positions, triangles);
    assert!(!crossing_pairs(&crown, &[0, 1]).is_empty());
    let mut src: Vec<u32> = (0..9).collect();
    src[0] = u32::MAX;
    let dist_in = vec![0.0; 9];
    let (trimmed, map, t) =
        trim_fringe(&crown, &src, &dist_in, 0.3, &[0, 1], Listed::Apex).unwrap();
    assert!(t.faces >= 1, "{t:?}");
    assert_eq!(boundary_loops(&trimmed).len(), 1);
    assert!(map.contains(&u32::MAX), "the apex is kept");
    assert!(
        crossing_pairs(
            &trimmed,
            &(0..trimmed.triangles.len() as u32).collect::<Vec<_>>()
        )
        .is_empty()
    );
}

/// A soup of small random triangles, some candidates: the binned search finds exactly the
/// pairs a test of every candidate against every face finds.
#[test]
fn crossing_pairs_are_every_crossing_of_a_candidate() {
    let mut rng = crate::phantom::rng::Rng::new(3);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for f in 0..400u32 {
        let c = DVec3::new(
            rng.range(0.0, 3.0),
            rng.range(0.0, 3.0),
            rng.range(0.0, 1.0),
        );
        for _ in 0..3 {
            positions.push(c + 0.3 * rng.unit_vector());
        }
        triangles.push([3 * f, 3 * f + 1, 3 * f + 2]);
    }
    let mesh = TriMesh::new(positions, triangles);
    let candidates: Vec<u32> = (0..400).filter(|f| f % 7 == 0).collect();
    let mut expect = Vec::new();
    for &f in &candidates {
        for g in 0..400u32 {
            if g != f && triangles_intersect(&mesh, f as usize, g as usize) {
                expect.push((f.min(g), f.max(g)));
            }
        }
    }
    expect.sort_unstable();
    expect.dedup();
    assert!(expect.len() > 20, "{} pairs", expect.len());
    assert_eq!(crossing_pairs(&mesh, &candidates), expect);
}

/// The crossing pairs a round takes over from the round before give the same trims as a search
/// of the crown every round, and peels that skip the whole crown's repair the same as peels that
/// repair it, on the rough phantom's crowns (folded slivers along the clipped margin, trimmed
/// over several rounds) with the fringe alone and with listed faces.
#[test]
fn carried_pairs_trim_as_a_fresh_search_does() {
    use crate::phantom::{IosExport, Phantom, PhantomOptions};
    let mut opts = PhantomOptions::default();
    opts.realism.ios.rough = IosExport::Rough.roughness();
    let p = Phantom::generate(&opts).expect("phantom generates");
    let mut carried_rounds = 0;
    let spared = SPARED.with(|s| s.get());
    for (fdi, crown) in p.ios_crowns().into_iter().take(6) {
        let inputs = crown.positions.len();
        let (crown, src, _) = repair_open_surface(&crown, &RepairOptions::default());
        let loops = boundary_loops(&crown);
        assert_eq!(loops.len(), 1, "tooth {fdi}");
        let d = edge_distance(&crown, &loops[0], 0.9);
        let mut dist_in = vec![f64::INFINITY; inputs];
        for (v, &s) in src.iter().enumerate() {
            if let Some(x) = dist_in.get_mut(s as usize) {
                *x = x.min(d[v]);
            }
        }
        // Some faces on the margin listed, as a band that crossed them would list them.
        let listed: Vec<u32> = (0..crown.triangles.len() as u32)
            .filter(|&f| {
                crown.triangles[f as usize]
                    .iter()
                    .any(|v| loops[0].contains(v))
            })
            .step_by(7)
            .collect();
        for extra in [&[][..], &listed[..]] {
            for mode in [Listed::Within, Listed::Apex] {
                let key = |r: &Option<(TriMesh, Vec<u32>, FringeTrim)>| {
                    r.as_ref().map(|(m, map, t)| {
                        (m.positions.clone(), m.triangles.clone(), map.clone(), *t)
                    })
                };
                let a = trim_rounds(&crown, &src, &dist_in, 0.3, extra, mode, Shortcuts::ALL);
                for (carry_pairs, skip_repair) in [(false, false), (true, false), (false, true)] {
                    let shortcuts = Shortcuts {
                        carry_pairs,
                        skip_repair,
                    };
                    let b = trim_rounds(&crown, &src, &dist_in, 0.3, extra, mode, shortcuts);
                    assert_eq!(
                        key(&a),
                        key(&b),
                        "tooth {fdi}, {mode:?}, {} listed, {shortcuts:?}",
                        extra.len()
                    );
                }
                carried_rounds += a.map_or(0, |(_, _, t)| t.rounds.saturating_sub(1));
            }
        }
    }
    assert!(carried_rounds > 0, "some trim ran more than one round");
    let spared = SPARED.with(|s| s.get()) - spared;
    assert!(
        spared > 10,
        "{spared} peels spared the whole crown's repair"
    );
}
