//! The scanner's software delivers crowns that do not pass through themselves: where a labeled
//! crown still does (a fold of bled gingiva along the margin, under noise), the faces at fault
//! are given to the gingiva and the crowns made disks again.

use super::crown_topology::make_crowns_disks;
use crate::mesh::{TriMesh, split_by_vertex_labels};
use crate::mesh_check::self_intersections;

/// Relabels (to gingiva, 0) the vertices of every crown face that intersects another face of the
/// same crown, then repairs the crowns' topology, until no crown self-intersects or `rounds`
/// are spent. Returns the number of crowns that still self-intersect.
pub fn untangle_crowns(
    mesh: &TriMesh,
    labels: &mut [i32],
    allow_holes: bool,
    rounds: usize,
) -> usize {
    let mut left = 0;
    let mut dirty: Option<Vec<i32>> = None;
    for round in 0..=rounds {
        let Ok(subs) = split_by_vertex_labels(mesh, labels) else {
            return usize::MAX;
        };
        let mut bad: Vec<u32> = Vec::new();
        let mut now_dirty = Vec::new();
        // Only the crowns relabeled in the last round can have changed.
        let check = |l: i32| l != 0 && dirty.as_ref().is_none_or(|d| d.contains(&l));
        // Each crown's crossings on its own (in parallel), gathered in label order.
        let crowns: Vec<_> = subs.iter().filter(|(l, _)| check(**l)).collect();
        let crossings = crate::par::map_ordered(&crowns, |(_, sub)| self_intersections(&sub.mesh));
        for ((&l, sub), pairs) in crowns.into_iter().zip(crossings) {
            if !pairs.is_empty() {
                now_dirty.push(l);
            }
            for (a, b) in pairs {
                for f in [a, b] {
                    bad.extend(
                        sub.mesh.triangles[f as usize]
                            .iter()
                            .map(|&v| sub.source_vertex[v as usize]),
                    );
                }
            }
        }
        left = now_dirty.len();
        dirty = Some(now_dirty);
        if bad.is_empty() || round == rounds {
            break;
        }
        for v in bad {
            labels[v as usize] = 0;
        }
        make_crowns_disks(mesh, labels, allow_holes);
    }
    left
}
