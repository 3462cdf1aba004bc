//! When removing faces from an open surface needs no repair afterwards. The fringe trim peels a
//! few faces at a time off a crown of tens of thousands, and [`repair_open_surface`] over the
//! whole crown after each peel costs far more than the peel. On a crown that repair would
//! leave as it is, taking faces away can only create two things it would change: a vertex left
//! with two fans (a bow-tie) and pieces cut off. Both are decided locally and by the boundary
//! loops, so the peel can skip the repair exactly where the repair would only have dropped the
//! unused vertices, and get the same mesh.
//!
//! [`repair_open_surface`]: super::repair_open_surface

use super::TriMesh;
use super::topology::{EdgeTopology, boundary_loops_of, connected_components_of};
use super::validate::FanScratch;
use glam::DVec3;

/// Whether [`repair_open_surface`] without hole filling would return `mesh` as it is, its unused
/// vertices dropped (`topo`: `mesh`'s topology). A sufficient test: every face has valid,
/// distinct corners and a non-zero cross product; no directed edge is used twice (so the faces
/// are oriented consistently, at most two share an edge, and none repeats the same way round);
/// at least three faces, all in one piece by shared edges (so none repeats the other way round:
/// two such faces share all three edges with nothing else and would be a piece of their own);
/// no vertex with two fans.
///
/// [`repair_open_surface`]: super::repair_open_surface
pub fn is_repaired(mesh: &TriMesh, topo: &EdgeTopology) -> bool {
    let n = mesh.positions.len();
    let nf = mesh.triangles.len();
    nf >= 3
        && mesh.triangles.iter().enumerate().all(|(f, t)| {
            t.iter().all(|&v| (v as usize) < n)
                && t[0] != t[1]
                && t[1] != t[2]
                && t[0] != t[2]
                && mesh.face_cross(f) != DVec3::ZERO
        })
        && super::repair::orientation_consistent(topo)
        && connected_components_of(topo, nf).1 == 1
        && super::validate::non_manifold_vertices_of(mesh, topo).is_empty()
}

/// `mesh` less the faces marked in `remove`: its vertices as they are, the other faces in their
/// order.
pub fn without_faces(mesh: &TriMesh, remove: &[bool]) -> TriMesh {
    let kept = mesh
        .triangles
        .iter()
        .zip(remove)
        .filter(|(_, r)| !**r)
        .map(|(t, _)| *t)
        .collect();
    TriMesh::new(mesh.positions.clone(), kept)
}

/// What [`taken_away`] gives: the surface left, as [`repair_open_surface`] would return it, with
/// its topology and boundary loops.
///
/// [`repair_open_surface`]: super::repair_open_surface
pub struct TakenAway {
    /// The faces kept, in their order, on the vertices they use (in their order).
    pub mesh: TriMesh,
    /// Per vertex of `mesh`, the vertex of the surface it came from.
    pub source: Vec<u32>,
    /// `mesh`'s topology.
    pub topo: EdgeTopology,
    /// `mesh`'s one boundary loop.
    pub loops: Vec<Vec<u32>>,
}

/// The faces of `mesh` not marked in `remove`, exactly as [`repair_open_surface`] without hole
/// filling returns them (with a clean report), or `None` when that is not certain and the repair
/// has to run. `mesh` must be one [`is_repaired`] says yes to (or one this function returned),
/// `topo` its topology.
///
/// Taking faces away from such a surface keeps every face valid and consistently oriented, with
/// no edge shared by three and no face repeated; what can change is a vertex of a removed face
/// left with two fans, checked here at each such vertex, and the surface falling apart. With no
/// vertex of two fans, every boundary vertex has one fan, so each boundary loop stays within one
/// piece; and every piece has a boundary edge (a piece without one would share no edge with the
/// rest, yet the surface was one piece and lost faces). So one boundary loop means one piece,
/// and the repair would only drop the unused vertices; the result is also a surface this
/// function accepts.
///
/// [`repair_open_surface`]: super::repair_open_surface
pub fn taken_away(mesh: &TriMesh, topo: &EdgeTopology, remove: &[bool]) -> Option<TakenAway> {
    let mut scratch = FanScratch::default();
    let mut block: Vec<(u32, u32, u32)> = Vec::new();
    let mut seen: Vec<u32> = Vec::new();
    for (t, _) in mesh.triangles.iter().zip(remove).filter(|(_, r)| **r) {
        seen.extend_from_slice(t);
    }
    seen.sort_unstable();
    seen.dedup();
    for &v in &seen {
        block.clear();
        block.extend(
            topo.leaving(v)
                .iter()
                .filter(|&&(_, _, f)| !remove[f as usize]),
        );
        if !block.is_empty() && !scratch.one_fan(mesh, v, &block) {
            return None;
        }
    }
    let mut left = without_faces(mesh, remove);
    let source = super::repair::compact_with_source(&mut left, |old| old as u32);
    let topo = EdgeTopology::new(&left);
    let loops = boundary_loops_of(&topo);
    (loops.len() == 1).then_some(TakenAway {
        mesh: left,
        source,
        topo,
        loops,
    })
}

/// [`repair_open_surface`] without hole filling of `mesh` less the faces marked in `remove`,
/// where `mesh` is a surface [`is_repaired`] says yes to and `topo` its topology: the
/// same mesh, map and report, with less work. Such a surface has no face with a bad corner or
/// no area, none twice and no edge of three faces, and taking faces away cannot make one, so
/// the first two steps would keep every face (and count nothing); and the faces left have the
/// surface's half-edges less the removed faces', in the same order.
///
/// [`repair_open_surface`]: super::repair_open_surface
pub(crate) fn repair_taken(
    mesh: &TriMesh,
    topo: &EdgeTopology,
    remove: &[bool],
) -> (TriMesh, Vec<u32>, super::RepairReport) {
    super::repair::repair_rest_unfilled(without_faces(mesh, remove), topo.without_faces(remove))
}

#[cfg(test)]
mod tests;
