//! The fold trimmed again at a wider reach, on the teeth of a coarse phantom export (crowns of
//! 0.3-0.5 mm edges that fold at their clipped margins).

use super::*;
use crate::fuse::cut_jaw;
use crate::phantom::{IosExport, Phantom, PhantomOptions};
use crate::stitch::BandVertex;
use std::collections::BTreeMap;

/// Per IOS input vertex of a crown: its position (the crown's vertices by `ios_vertex`).
fn by_input(crown: &crate::mesh::TriMesh, ios_vertex: &[u32]) -> BTreeMap<u32, glam::DVec3> {
    ios_vertex
        .iter()
        .zip(&crown.positions)
        .filter(|(s, _)| **s != u32::MAX)
        .map(|(&s, &p)| (s, p))
        .collect()
}

#[test]
fn a_wider_fold_trim_takes_only_vertices_within_its_reach_and_counts_them() {
    let mut po = PhantomOptions {
        seed: 8,
        jaw: crate::arch::Jaw::Lower,
        ..PhantomOptions::default()
    };
    po.realism.ios.rough = IosExport::Coarse.roughness();
    let p = Phantom::generate(&po).expect("phantom");
    let tr = crate::eval::true_transforms(&p);
    let opts = FuseOptions::default();
    let cut = cut_jaw(&p.ios, &p.cbct, &tr, &opts).expect("cut");
    let mut trimmed_teeth = 0;
    for ct in cut.teeth.values() {
        for factor in LAST_RESORT_REACH {
            let reach = opts.fringe_reach_mm * factor;
            let Some(w) = wider_fold(ct, reach) else {
                continue;
            };
            trimmed_teeth += 1;
            let tag = format!("tooth {} reach {reach}", ct.fdi);
            // One margin, the crown's only boundary loop.
            assert_eq!(boundary_loops(&w.crown), vec![w.margin.clone()], "{tag}");
            assert_eq!(w.crown_dirs.len(), w.margin.len(), "{tag}");
            // Every vertex kept is an input vertex of the crown as cut, bitwise where it was.
            let before = by_input(&ct.crown, &ct.ios_vertex);
            let after = by_input(&w.crown, &w.ios_vertex);
            for (s, q) in &after {
                assert_eq!(before.get(s), Some(q), "{tag}: input vertex {s}");
            }
            // The vertices gone lie within the reach and are counted.
            let lost: Vec<u32> = before
                .keys()
                .copied()
                .filter(|s| !after.contains_key(s))
                .collect();
            assert!(
                !lost.is_empty() || w.trimmed.faces > ct.trimmed.faces,
                "{tag}"
            );
            for s in &lost {
                assert!(ct.dist_in[*s as usize] <= reach, "{tag}: input vertex {s}");
            }
            assert_eq!(
                w.trimmed.vertices,
                ct.trimmed.vertices + lost.len(),
                "{tag}"
            );
            assert_eq!(w.kept_ios, ct.kept_ios - lost.len(), "{tag}");
            // The root side is the cut's; the crown's chords index the new margin.
            let lower = |c: &[(BandVertex, BandVertex)]| -> Vec<(BandVertex, BandVertex)> {
                c.iter()
                    .copied()
                    .filter(|c| matches!(c.0, BandVertex::Lower(_)))
                    .collect()
            };
            assert_eq!(lower(&w.chords), lower(&ct.chords), "{tag}");
            for c in &w.chords {
                if let (BandVertex::Upper(a), BandVertex::Upper(b)) = c {
                    assert!(
                        (*a as usize) < w.margin.len() && (*b as usize) < w.margin.len(),
                        "{tag}"
                    );
                }
            }
            assert_eq!(w.root.cut_loop, ct.root.cut_loop, "{tag}");
            let said = w.warnings.last().expect("a warning");
            assert!(said.contains(&format!("within {reach:.2} mm")), "{said}");
        }
    }
    assert!(
        trimmed_teeth >= 3,
        "{trimmed_teeth} teeth with a fold within the wider reaches"
    );
}
