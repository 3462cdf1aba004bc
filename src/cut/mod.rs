//! Crown removal (paper section 2.3.1): the CBCT tooth is split along a closed loop near the
//! IOS gingival margin and its crown side removed, keeping the root as a disk bounded by exactly
//! one simple loop.
//!
//! Two methods: [`CutMethod::Dijkstra`] is the paper's (nearest CBCT vertices to the margin
//! points joined by Dijkstra shortest paths, mesh split along the path);
//! [`CutMethod::LevelSet`] (ours) cuts along the level set "height below the margin's windowed
//! minimum height at this angle, minus the offset", which stays below the margin everywhere by
//! construction. Both finish with [`region::clean_root_region`], so the root is always a disk.

pub mod dijkstra;
mod frame;
pub mod region;

pub use frame::{MarginHeight, ToothFrame};

use crate::mesh::{TriMesh, ValidateOptions, boundary_loops};
use crate::{Error, Result};
use glam::DVec3;

/// How the cut loop is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CutMethod {
    /// Paper: nearest CBCT vertices to the (offset) margin points, joined by Dijkstra paths.
    Dijkstra,
    /// Ours: vertex level set of the height below the windowed-minimum margin height.
    LevelSet,
}

/// Options of the crown cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutOptions {
    /// Method.
    pub method: CutMethod,
    /// Distance (mm) along the tooth axis toward the root between the IOS margin and the cut,
    /// room for the stitching band to blend. Must be ≥ 0.
    pub offset: f64,
    /// Half-width (radians) of the running minimum of the margin height used by
    /// [`CutMethod::LevelSet`].
    pub window: f64,
    /// Steepest climb of [`CutMethod::LevelSet`]'s cut along the tooth (height per unit of
    /// length around it; 1 = 45°), where the margin climbs a contact's flank faster; 0: none
    /// (see [`MarginHeight::new`]). None by default: the fusion cuts a tooth again with a bound
    /// only where its band is left crossed.
    pub max_slope: f64,
}

impl Default for CutOptions {
    fn default() -> Self {
        Self {
            method: CutMethod::LevelSet,
            offset: 0.8,
            window: 0.15,
            max_slope: 0.0,
        }
    }
}

/// The root part of a CBCT tooth after crown removal.
#[derive(Clone, Debug)]
pub struct RootCut {
    /// The kept root: an open disk-like mesh (CBCT positions unchanged).
    pub root: TriMesh,
    /// For each root vertex, its index in the input CBCT mesh.
    pub source_vertex: Vec<u32>,
    /// The root's single boundary loop (root vertex indices), in the order of
    /// [`boundary_loops`] (root surface on the left).
    pub cut_loop: Vec<u32>,
    /// Number of CBCT faces removed (the crown side).
    pub removed_faces: usize,
}

/// Removes the crown side of the closed CBCT tooth `cbct` along the IOS margin `margin`
/// (closed polyline, same frame as `cbct`), using `frame` for the root → crown direction.
pub fn cut_crown(
    cbct: &TriMesh,
    margin: &[DVec3],
    frame: &ToothFrame,
    opts: &CutOptions,
) -> Result<RootCut> {
    if !(opts.offset >= 0.0 && opts.offset.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "cut offset must be a finite number ≥ 0 mm, got {}",
            opts.offset
        )));
    }
    // The checks of `validate` (same errors), keeping the edge topology for the adjacency.
    let topo = cbct.validate_into_topology(&ValidateOptions {
        require_closed: true,
        allow_zero_area: true,
    })?;
    let adj = region::face_adjacency_of(cbct, &topo)?;
    drop(topo);
    let h: Vec<f64> = cbct.positions.iter().map(|&p| frame.height(p)).collect();
    let (root_seed, crown_seed) = seeds(cbct, &h)?;
    let rough: Vec<bool> = match opts.method {
        CutMethod::LevelSet => below_level(cbct, &h, margin, frame, opts),
        CutMethod::Dijkstra => root_side_of_path(cbct, &adj, margin, frame, opts, root_seed)?,
    };
    let root_mask = region::clean_root_region(cbct, &adj, rough, root_seed, crown_seed)?;
    root_of(cbct, &root_mask)
}

/// The seed faces of the root and crown sides: the face with the lowest highest corner (apex)
/// and the face with the highest lowest corner (top), by the heights `h` along the axis.
fn seeds(cbct: &TriMesh, h: &[f64]) -> Result<(u32, u32)> {
    let key = |f: usize, hi: bool| {
        let t = cbct.triangles[f];
        let v = t.map(|i| h[i as usize]);
        if hi {
            v[0].max(v[1]).max(v[2])
        } else {
            v[0].min(v[1]).min(v[2])
        }
    };
    let nf = cbct.triangles.len();
    let root_seed = (0..nf)
        .min_by(|&a, &b| key(a, true).total_cmp(&key(b, true)))
        .ok_or_else(|| Error::InvalidArgument("CBCT tooth has no faces".into()))?
        as u32;
    let crown_seed = (0..nf)
        .max_by(|&a, &b| key(a, false).total_cmp(&key(b, false)))
        .unwrap_or(0) as u32;
    Ok((root_seed, crown_seed))
}

/// [`CutMethod::LevelSet`]: per face, whether every corner lies below the margin's height at
/// its angle about the axis, less the offset.
fn below_level(
    cbct: &TriMesh,
    h: &[f64],
    margin: &[DVec3],
    frame: &ToothFrame,
    opts: &CutOptions,
) -> Vec<bool> {
    let mh = MarginHeight::new(frame, margin, opts.window, opts.max_slope);
    let below: Vec<bool> = cbct
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| h[i] < mh.at(frame.angle(p)) - opts.offset)
        .collect();
    cbct.triangles
        .iter()
        .map(|t| t.iter().all(|&v| below[v as usize]))
        .collect()
}

/// [`CutMethod::Dijkstra`]: per face, whether it is reached from the root seed without
/// crossing the closed shortest path through the CBCT vertices nearest to the margin (moved
/// down the axis by the offset).
fn root_side_of_path(
    cbct: &TriMesh,
    adj: &[[u32; 3]],
    margin: &[DVec3],
    frame: &ToothFrame,
    opts: &CutOptions,
    root_seed: u32,
) -> Result<Vec<bool>> {
    let targets: Vec<DVec3> = margin
        .iter()
        .map(|&p| p - frame.axis * opts.offset)
        .collect();
    let anchors = dijkstra::nearest_vertices(cbct, &targets);
    if anchors.len() < 3 {
        return Err(Error::InvalidArgument(
            "margin maps to fewer than 3 distinct CBCT vertices".into(),
        ));
    }
    let nb = dijkstra::vertex_neighbours(cbct);
    let path = dijkstra::closed_path(cbct, &nb, &anchors)
        .ok_or_else(|| Error::InvalidArgument("CBCT tooth mesh graph is not connected".into()))?;
    let mut cut_edges: Vec<(u32, u32)> = (0..path.len())
        .map(|i| {
            let (a, b) = (path[i], path[(i + 1) % path.len()]);
            (a.min(b), a.max(b))
        })
        .collect();
    cut_edges.sort_unstable();
    cut_edges.dedup();
    let all = vec![true; cbct.triangles.len()];
    Ok(region::flood(adj, &all, root_seed, |f, k| {
        let t = cbct.triangles[f];
        let (a, b) = (t[k], t[(k + 1) % 3]);
        cut_edges.binary_search(&(a.min(b), a.max(b))).is_ok()
    }))
}

/// The root: the faces of `root_mask`, compacted, with each vertex's input index; an error
/// unless it has exactly one boundary loop and that loop is simple.
fn root_of(cbct: &TriMesh, root_mask: &[bool]) -> Result<RootCut> {
    let nf = cbct.triangles.len();
    let mut root = TriMesh::new(
        cbct.positions.clone(),
        (0..nf)
            .filter(|&f| root_mask[f])
            .map(|f| cbct.triangles[f])
            .collect(),
    );
    let removed_faces = nf - root.triangles.len();
    let map = root.compact();
    let mut source_vertex = vec![0u32; root.positions.len()];
    for (old, &new) in map.iter().enumerate() {
        if new != u32::MAX {
            source_vertex[new as usize] = old as u32;
        }
    }
    let loops = boundary_loops(&root);
    if loops.len() != 1 {
        return Err(Error::InvalidArgument(format!(
            "crown cut produced {} boundary loops on the CBCT root, expected 1",
            loops.len()
        )));
    }
    let cut_loop = loops.into_iter().next().unwrap_or_default();
    let mut sorted = cut_loop.clone();
    sorted.sort_unstable();
    if sorted.windows(2).any(|w| w[0] == w[1]) || cut_loop.len() < 3 {
        return Err(Error::InvalidArgument(
            "crown cut loop is not simple".into(),
        ));
    }
    Ok(RootCut {
        root,
        source_vertex,
        cut_loop,
        removed_faces,
    })
}
