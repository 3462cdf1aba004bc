//! One peel of the fringe trim: the marked faces taken off the crown and what is left made one
//! disk again; a removal that would pinch the crown, open a second loop or lose a vertex beyond
//! the reach is put back.

use crate::mesh::{
    EdgeTopology, RepairOptions, TakenAway, TriMesh, boundary_loops_of, repair_open_surface,
    repair_taken, sorted_corners, taken_away, without_faces,
};
use std::cmp::Reverse;

/// What [`peel`] made.
pub(super) struct Peeled {
    /// The trimmed crown.
    pub(super) crown: TriMesh,
    /// Its vertices' input indices.
    pub(super) map: Vec<u32>,
    /// Faces removed.
    pub(super) removed: usize,
    /// Per face of `crown`, its index in the crown before the peel, where the repair only took
    /// faces away (no vertex split, no face turned, nothing added); `None` otherwise.
    pub(super) face_of: Option<Vec<u32>>,
    /// The trimmed crown's topology.
    pub(super) topo: EdgeTopology,
    /// Whether the trimmed crown is known to be one the repair would leave as it is (it was
    /// taken from such a crown without needing the repair, see [`taken_away`]).
    pub(super) repaired: bool,
}

/// Per face of `rep` (the repair of `cut`, the crown's faces left by `remove`, with `rep_src`
/// its vertices' indices in the crown), its index in the crown, found by walking both face
/// lists in order; `None` where a face of `rep` is not the next of the crown's kept faces (the
/// repair did more than take faces away).
fn faces_kept(
    crown: &TriMesh,
    remove: &[bool],
    rep: &TriMesh,
    rep_src: &[u32],
) -> Option<Vec<u32>> {
    let mut kept = crown
        .triangles
        .iter()
        .zip(remove)
        .enumerate()
        .filter(|(_, (_, r))| !**r)
        .map(|(f, (t, _))| (f as u32, *t));
    rep.triangles
        .iter()
        .map(|t| {
            let want = t.map(|v| rep_src[v as usize]);
            kept.find(|&(_, k)| k == want).map(|(f, _)| f)
        })
        .collect()
}

#[cfg(test)]
thread_local! {
    /// Peels on this thread that did not repair the whole crown (tests: the shortcut is taken).
    pub(super) static SPARED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Times [`peel`] puts back the marked faces at a pinch and tries again.
const PEEL_RETRIES: usize = 4;

/// Removes the faces marked in `remove` from `mesh` (whose vertices' input indices are `map`)
/// and repairs what is left. The result must stay one disk losing nothing beyond the reach:
/// where the removal leaves several boundary loops, or the repair drops a piece cut off by it
/// that holds a vertex beyond the reach, the marked faces touching the culprit vertices (those
/// of the extra loops, or of the dropped pieces) are kept instead and the rest is tried again,
/// so that one pinching face does not hold back the whole round. `None` when nothing can go.
/// `repaired`: `mesh`'s topology when `mesh` is one the repair would leave as it is; then a
/// removal [`taken_away`] can vouch for is not repaired (the repair would only drop the unused
/// vertices: the same crown).
pub(super) fn peel(
    mesh: &TriMesh,
    map: &[u32],
    remove: &mut [bool],
    dist_in: &[f64],
    reach: f64,
    repaired: Option<&EdgeTopology>,
) -> Option<Peeled> {
    let n = mesh.positions.len();
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    for _ in 0..PEEL_RETRIES {
        let removed = remove.iter().filter(|&&r| r).count();
        if removed == 0 {
            return None;
        }
        #[cfg(test)]
        if repaired.is_some() {
            SPARED.with(|s| s.set(s.get() + 1));
        }
        let taken = repaired.and_then(|topo| taken_away(mesh, topo, remove));
        let fast = taken.is_some();
        let (rep, rep_src, done, rep_topo, loops) = match taken {
            Some(TakenAway {
                mesh,
                source,
                topo,
                loops,
            }) => (mesh, source, Default::default(), topo, loops),
            None => {
                let (rep, rep_src, done) = match repaired {
                    Some(topo) => repair_taken(mesh, topo, remove),
                    None => repair_open_surface(
                        &without_faces(mesh, remove),
                        &RepairOptions {
                            max_hole_fraction: 0.0,
                        },
                    ),
                };
                let topo = EdgeTopology::new(&rep);
                let loops = boundary_loops_of(&topo);
                (rep, rep_src, done, topo, loops)
            }
        };
        let mut present = vec![false; n];
        for &s in rep_src.iter().filter(|&&s| s != u32::MAX) {
            present[s as usize] = true;
        }
        let far = |v: usize| map[v] != u32::MAX && dist_in[map[v] as usize] > reach;
        let mut culprit = vec![false; n];
        if (0..n).any(|v| used[v] && !present[v] && far(v)) {
            // The corners of every kept face the repair dropped (the pieces the removal cut
            // off), and the far vertices whose faces all went.
            let mut left: Vec<[u32; 3]> = rep
                .triangles
                .iter()
                .map(|t| sorted_corners(t.map(|v| rep_src[v as usize])))
                .collect();
            left.sort_unstable();
            let kept = mesh
                .triangles
                .iter()
                .zip(remove.iter())
                .filter(|(_, r)| !**r);
            for (t, _) in kept {
                if left.binary_search(&sorted_corners(*t)).is_err() {
                    for &v in t {
                        culprit[v as usize] = true;
                    }
                }
            }
            for (v, c) in culprit.iter_mut().enumerate() {
                *c |= used[v] && !present[v] && far(v);
            }
        }
        if loops.len() > 1 {
            let longest = (0..loops.len())
                .max_by_key(|&i| (loops[i].len(), Reverse(i)))
                .unwrap_or(0);
            for (i, lp) in loops.iter().enumerate() {
                if i != longest {
                    for &v in lp {
                        if let Some(&s) = rep_src.get(v as usize).filter(|&&s| s != u32::MAX) {
                            culprit[s as usize] = true;
                        }
                    }
                }
            }
        }
        if !culprit.iter().any(|&c| c) {
            if loops.len() != 1 {
                return None;
            }
            let next = rep_src
                .iter()
                .map(|&s| {
                    if s == u32::MAX {
                        u32::MAX
                    } else {
                        map[s as usize]
                    }
                })
                .collect();
            let only_taken = done.split_vertices == 0
                && done.flipped_faces == 0
                && done.filled_holes == 0
                && done.added_vertices == 0;
            let face_of = only_taken
                .then(|| faces_kept(mesh, remove, &rep, &rep_src))
                .flatten();
            return Some(Peeled {
                crown: rep,
                map: next,
                removed,
                face_of,
                topo: rep_topo,
                repaired: fast,
            });
        }
        let mut restored = 0;
        for (t, r) in mesh.triangles.iter().zip(remove.iter_mut()) {
            if *r && t.iter().any(|&v| culprit[v as usize]) {
                *r = false;
                restored += 1;
            }
        }
        if restored == 0 {
            return None;
        }
    }
    None
}
