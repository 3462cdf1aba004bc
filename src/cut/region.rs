//! Turning a rough "root side" face set on a closed CBCT tooth into a clean disk: one connected
//! root region holding the apex, one connected crown region holding the occlusal top, and a
//! single simple boundary loop between them (no ears, no pinched vertices).

use crate::mesh::{EdgeTopology, TriMesh};
use crate::{Error, Result};

/// Face adjacency of a closed manifold mesh: `adj[f][k]` is the face across edge
/// `t[k] → t[k+1]`.
pub fn face_adjacency(mesh: &TriMesh) -> Result<Vec<[u32; 3]>> {
    face_adjacency_of(mesh, &EdgeTopology::new(mesh))
}

/// [`face_adjacency`] from an already built topology of `mesh`.
pub fn face_adjacency_of(mesh: &TriMesh, topo: &EdgeTopology) -> Result<Vec<[u32; 3]>> {
    let mut adj = vec![[u32::MAX; 3]; mesh.triangles.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let mut it = topo.faces_of_directed(b, a);
            match (it.next(), it.next()) {
                (Some(g), None) => adj[f][k] = g,
                _ => {
                    return Err(Error::NonManifoldEdge {
                        a,
                        b,
                        faces: topo.edge_face_count(a, b),
                    });
                }
            }
        }
    }
    Ok(adj)
}

/// Faces reachable from `seed` through faces where `inside` holds, crossing no edge for which
/// `blocked(f, k)` holds.
pub fn flood(
    adj: &[[u32; 3]],
    inside: &[bool],
    seed: u32,
    blocked: impl Fn(usize, usize) -> bool,
) -> Vec<bool> {
    let mut seen = vec![false; adj.len()];
    if !inside[seed as usize] {
        return seen;
    }
    let mut stack = vec![seed];
    seen[seed as usize] = true;
    while let Some(f) = stack.pop() {
        for (k, &g) in adj[f as usize].iter().enumerate() {
            if !seen[g as usize] && inside[g as usize] && !blocked(f as usize, k) {
                seen[g as usize] = true;
                stack.push(g);
            }
        }
    }
    seen
}

/// Cleans `root` (a face mask) so that it is a disk bounded by one simple loop: connected and
/// holding `root_seed`, with a connected complement holding `crown_seed`, no root face with two
/// or more crown neighbours (ears), and no vertex where the boundary passes twice.
pub fn clean_root_region(
    mesh: &TriMesh,
    adj: &[[u32; 3]],
    mut root: Vec<bool>,
    root_seed: u32,
    crown_seed: u32,
) -> Result<Vec<bool>> {
    let nf = mesh.triangles.len();
    for _round in 0..200 {
        if !root[root_seed as usize] || root[crown_seed as usize] {
            return Err(Error::InvalidArgument(
                "crown cut leaves no root or no crown (margin does not cross the CBCT tooth)"
                    .into(),
            ));
        }
        root = flood(adj, &root, root_seed, |_, _| false);
        let crown_mask: Vec<bool> = root.iter().map(|r| !r).collect();
        let crown = flood(adj, &crown_mask, crown_seed, |_, _| false);
        for f in 0..nf {
            root[f] = !crown[f];
        }
        let mut changed = false;
        // Ears: root faces with two or more crown neighbours go to the crown side.
        loop {
            let mut any = false;
            for f in 0..nf {
                if root[f] && f as u32 != root_seed {
                    let c = adj[f].iter().filter(|&&g| !root[g as usize]).count();
                    if c >= 2 {
                        root[f] = false;
                        any = true;
                    }
                }
            }
            if !any {
                break;
            }
            changed = true;
        }
        // Pinched vertices: more than two boundary edges meet there.
        let mut count = vec![0u32; mesh.positions.len()];
        for f in 0..nf {
            if !root[f] {
                continue;
            }
            let t = mesh.triangles[f];
            for k in 0..3 {
                if !root[adj[f][k] as usize] {
                    count[t[k] as usize] += 1;
                    count[t[(k + 1) % 3] as usize] += 1;
                }
            }
        }
        let pinched: Vec<bool> = count.iter().map(|&c| c > 2).collect();
        if pinched.iter().any(|&p| p) {
            for (f, r) in root.iter_mut().enumerate() {
                if *r
                    && f as u32 != root_seed
                    && mesh.triangles[f].iter().any(|&v| pinched[v as usize])
                {
                    *r = false;
                }
            }
            changed = true;
        }
        if !changed {
            return Ok(root);
        }
    }
    Err(Error::DidNotConverge(
        "crown cut: the root region could not be made a disk with one simple boundary".into(),
    ))
}
