//! Rough IOS exports: what other scanners and segmentation tools hand a host instead of the
//! project's clean scan. The surface-nets mesh is kept raw (no relaxation, so its slivers stay),
//! crowns are not cleaned of the folds the noise makes, the crown/gingiva label boundary is
//! clipped through the triangles (new vertices on the boundary curve, tiny slivers along the
//! margin), notches reach the margin, holes are punched, the labels carry a segmentation tool's
//! noise (tooth-labelled islands in the gingiva, gingiva-labelled holes in the crowns; each crown
//! stays manifold: pinch vertices go to the gingiva), and the density can be coarse, 2x, 4x or
//! midpoint-subdivided.

use super::rng::Rng;
use crate::mesh::TriMesh;
use glam::DVec3;
use std::collections::HashMap;

/// Named IOS exports: the clean scan (default) and rough ones (see [`IosRoughness`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum IosExport {
    /// The project's scan: relaxed vertices, crowns cleaned of crossings, one disk per crown.
    #[default]
    Clean,
    /// Raw surface nets with marching-cubes-like slivers at the scan spacing (~0.17 mm edges)
    /// with every roughness of [`IosRoughness::rough`].
    Rough,
    /// Rough at a coarse spacing (0.45 mm grid, ~0.45 mm mean crown edge), standing for a
    /// decimated export (it is a coarse scan, not an edge-collapse decimation).
    Coarse,
    /// Rough at 2x the vertex density (grid spacing / √2, ~0.14 mm edges), noise 0.014 mm (a
    /// denser scanner is no noisier per vertex: the noise shrinks with the spacing).
    Dense2,
    /// Rough at 4x the vertex density (grid spacing / 2, ~0.11 mm edges, like the foreign jaws),
    /// noise 0.01 mm.
    Dense4,
    /// [`IosExport::Dense2`], then one midpoint subdivision (~8x the rough vertices, ~0.07 mm
    /// edges, coplanar face quadruples), like a re-meshed denser export.
    Subdivided,
}

impl IosExport {
    /// Every export, for sweeps.
    pub const ALL: [IosExport; 6] = [
        IosExport::Clean,
        IosExport::Rough,
        IosExport::Coarse,
        IosExport::Dense2,
        IosExport::Dense4,
        IosExport::Subdivided,
    ];

    /// The rough exports (every one but [`IosExport::Clean`]).
    pub const ROUGH: [IosExport; 5] = [
        IosExport::Rough,
        IosExport::Coarse,
        IosExport::Dense2,
        IosExport::Dense4,
        IosExport::Subdivided,
    ];

    /// Command-line name (`clean`, `rough`, `coarse`, `dense2`, `dense4`, `subdivided`).
    pub fn name(self) -> &'static str {
        match self {
            IosExport::Clean => "clean",
            IosExport::Rough => "rough",
            IosExport::Coarse => "coarse",
            IosExport::Dense2 => "dense2",
            IosExport::Dense4 => "dense4",
            IosExport::Subdivided => "subdivided",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<IosExport> {
        IosExport::ALL.into_iter().find(|e| e.name() == s)
    }

    /// The roughness of this export (`None` for the clean scan): the value for
    /// [`super::IosRealism::rough`].
    pub fn roughness(self) -> Option<IosRoughness> {
        let rough = IosRoughness::rough();
        match self {
            IosExport::Clean => None,
            IosExport::Rough => Some(rough),
            IosExport::Coarse => Some(IosRoughness {
                density: (0.18f64 / 0.45).powi(2),
                ..rough
            }),
            IosExport::Dense2 => Some(IosRoughness {
                density: 2.0,
                noise: 0.014,
                ..rough
            }),
            IosExport::Dense4 => Some(IosRoughness {
                density: 4.0,
                noise: 0.01,
                ..rough
            }),
            IosExport::Subdivided => Some(IosRoughness {
                density: 2.0,
                noise: 0.014,
                subdivisions: 1,
                ..rough
            }),
        }
    }
}

/// How a rough IOS export departs from the clean scan. Counts given per tooth are rounded up
/// per jaw (`ceil(rate × IOS teeth)`), so every jaw, a partial arch too, carries each kind.
#[derive(Clone, Debug, PartialEq)]
pub struct IosRoughness {
    /// Vertex density relative to the clean scan: the surface-nets grid spacing is
    /// `IosRealism::spacing / √density`.
    pub density: f64,
    /// Standard deviation of the isotropic per-vertex noise (mm, clamped at 2.5 sigma); it
    /// replaces [`super::IosRealism::noise`] and, on the raw slivers, folds the crowns.
    pub noise: f64,
    /// Clip the label boundary through the triangles: every edge whose ends carry different
    /// labels is cut where the labelling level crosses zero, the new vertex takes the tooth's
    /// label, so each crown ends on the cut curve with slivers along it.
    pub clip_margin: bool,
    /// Midpoint subdivisions of the finished export (each: 4x the faces, coplanar quadruples).
    pub subdivisions: u32,
    /// Holes punched through the mesh in crowns, per tooth.
    pub mesh_holes: f64,
    /// Notches (0.3–0.5 mm radius) cut through the mesh across the margin, per tooth.
    pub margin_notches: f64,
    /// Stray tooth-labelled islands (0.12–0.3 mm radius, at least the grid spacing) in the
    /// gingiva 0.5–1 mm beyond their radius off a crown, per tooth.
    pub label_islands: f64,
    /// Gingiva-labelled holes (0.1–0.3 mm radius, at least the grid spacing) inside crowns, per
    /// tooth.
    pub label_holes: f64,
}

impl IosRoughness {
    /// The rough export at the clean scan's density.
    pub fn rough() -> Self {
        IosRoughness {
            density: 1.0,
            noise: 0.02,
            clip_margin: true,
            subdivisions: 0,
            mesh_holes: 0.15,
            margin_notches: 0.3,
            label_islands: 0.4,
            label_holes: 0.4,
        }
    }

    /// Number of a kind of defect on a jaw of `teeth` IOS teeth.
    fn count(rate: f64, teeth: usize) -> usize {
        (rate * teeth as f64).ceil() as usize
    }
}

/// Vertex neighbours of a mesh (sorted, deduplicated).
fn neighbours(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            adj[a as usize].push(b);
            adj[b as usize].push(a);
        }
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    adj
}

/// Drops unused vertices, carrying the per-vertex `labels` and `level` along.
fn compact(mesh: &mut TriMesh, labels: &mut Vec<i32>, level: &mut Vec<f64>) {
    let map = mesh.compact();
    let n = mesh.positions.len();
    let (mut nl, mut nv) = (vec![0; n], vec![0.0; n]);
    for (old, &new) in map.iter().enumerate() {
        if new != u32::MAX {
            nl[new as usize] = labels[old];
            nv[new as usize] = level[old];
        }
    }
    *labels = nl;
    *level = nv;
}

/// Vertices labelled `fdi` with a neighbour labelled otherwise (the crown's label boundary).
fn boundary_of(adj: &[Vec<u32>], labels: &[i32], fdi: i32) -> Vec<u32> {
    (0..labels.len())
        .filter(|&v| labels[v] == fdi && adj[v].iter().any(|&w| labels[w as usize] != fdi))
        .map(|v| v as u32)
        .collect()
}

/// Vertices labelled `within` reached from `seed` (labelled `within` too) whose distance to
/// `centre` is at most `r`, by a search through such vertices.
fn ball(
    mesh: &TriMesh,
    adj: &[Vec<u32>],
    labels: &[i32],
    within: i32,
    seed: u32,
    centre: DVec3,
    r: f64,
) -> Vec<u32> {
    let mut seen = vec![seed];
    let mut stack = vec![seed];
    while let Some(v) = stack.pop() {
        for &w in &adj[v as usize] {
            if labels[w as usize] == within
                && (mesh.positions[w as usize] - centre).length() <= r
                && !seen.contains(&w)
            {
                seen.push(w);
                stack.push(w);
            }
        }
    }
    seen
}

/// Removes the faces with a vertex within `r` of the segment `a`–`b`.
fn cut_faces_near_segment(mesh: &mut TriMesh, a: DVec3, b: DVec3, r: f64) {
    let ab = b - a;
    let dist = |p: DVec3| {
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        (p - (a + ab * t)).length()
    };
    let pos = &mesh.positions;
    mesh.triangles
        .retain(|t| t.iter().all(|&v| dist(pos[v as usize]) >= r));
}

/// Removes the faces with a vertex within `r` of `c`.
fn cut_faces_near_point(mesh: &mut TriMesh, c: DVec3, r: f64) {
    cut_faces_near_segment(mesh, c, c + DVec3::splat(1e-9), r);
}

/// Makes a labelled, relaxation-free IOS jaw rough (see [`IosRoughness`]): holes and notches
/// through the mesh, crowns made disks, label noise, per-vertex noise, the margin clipped
/// through the triangles, subdivisions. `level` is the labelling level per vertex (negative on
/// the tooth side of the label boundary); `fdis` are the IOS teeth; `occ` the occlusal direction;
/// `h` the grid spacing (label islands and holes are at least that wide, so that they hold
/// faces on a coarse mesh).
#[allow(clippy::too_many_arguments)]
pub fn roughen(
    mesh: &mut TriMesh,
    labels: &mut Vec<i32>,
    mut level: Vec<f64>,
    fdis: &[u8],
    occ: DVec3,
    h: f64,
    rough: &IosRoughness,
    rng: &mut Rng,
) {
    let n_teeth = fdis.len().max(1);
    let pick_tooth = |rng: &mut Rng| fdis[rng.below(fdis.len())] as i32;
    if fdis.is_empty() {
        return;
    }
    // Holes through the crowns and notches across the margin.
    let adj = neighbours(mesh);
    for _ in 0..IosRoughness::count(rough.mesh_holes, n_teeth) {
        let fdi = pick_tooth(rng);
        let crown: Vec<usize> = (0..labels.len()).filter(|&v| labels[v] == fdi).collect();
        let r = rng.range(0.2, 0.4);
        if crown.is_empty() {
            continue;
        }
        let c = mesh.positions[crown[rng.below(crown.len())]];
        cut_faces_near_point(mesh, c, r);
    }
    for _ in 0..IosRoughness::count(rough.margin_notches, n_teeth) {
        let fdi = pick_tooth(rng);
        let edge = boundary_of(&adj, labels, fdi);
        let r = rng.range(0.3, 0.5);
        if edge.is_empty() {
            continue;
        }
        let m = mesh.positions[edge[rng.below(edge.len())] as usize];
        cut_faces_near_segment(mesh, m - occ * 0.8, m + occ * 0.8, r);
    }
    compact(mesh, labels, &mut level);
    super::crown_topology::make_crowns_disks(mesh, labels, true);
    // A segmentation tool's label noise.
    let adj = neighbours(mesh);
    for _ in 0..IosRoughness::count(rough.label_islands, n_teeth) {
        let fdi = pick_tooth(rng);
        let edge = boundary_of(&adj, labels, fdi);
        let r = rng.range(0.12, 0.3).max(h);
        let off = rng.range(0.5, 1.0) + r;
        if edge.is_empty() {
            continue;
        }
        let m = edge[rng.below(edge.len())];
        let pm = mesh.positions[m as usize];
        // Through the gingiva from the margin vertex to the first vertex `off` away from it.
        let mut seen = vec![false; labels.len()];
        let mut queue = std::collections::VecDeque::from([m]);
        seen[m as usize] = true;
        let mut centre = None;
        while let Some(v) = queue.pop_front() {
            if labels[v as usize] == 0 && (mesh.positions[v as usize] - pm).length() >= off {
                centre = Some(v);
                break;
            }
            for &w in &adj[v as usize] {
                if labels[w as usize] == 0 && !seen[w as usize] {
                    seen[w as usize] = true;
                    queue.push_back(w);
                }
            }
        }
        if let Some(c) = centre {
            let pc = mesh.positions[c as usize];
            for v in ball(mesh, &adj, labels, 0, c, pc, r) {
                labels[v as usize] = fdi;
                level[v as usize] = -level[v as usize].abs();
            }
        }
    }
    for _ in 0..IosRoughness::count(rough.label_holes, n_teeth) {
        let fdi = pick_tooth(rng);
        let r = rng.range(0.1, 0.3).max(h);
        // Hops from the crown's label boundary, within the crown.
        let mut hops = vec![u32::MAX; labels.len()];
        let mut queue: std::collections::VecDeque<u32> =
            boundary_of(&adj, labels, fdi).into_iter().collect();
        for &v in &queue {
            hops[v as usize] = 0;
        }
        while let Some(v) = queue.pop_front() {
            for &w in &adj[v as usize] {
                if labels[w as usize] == fdi && hops[w as usize] == u32::MAX {
                    hops[w as usize] = hops[v as usize] + 1;
                    queue.push_back(w);
                }
            }
        }
        let inner: Vec<u32> = (0..labels.len())
            .filter(|&v| (3..=12).contains(&hops[v]))
            .map(|v| v as u32)
            .collect();
        if inner.is_empty() {
            continue;
        }
        let c = inner[rng.below(inner.len())];
        let pc = mesh.positions[c as usize];
        for v in ball(mesh, &adj, labels, fdi, c, pc, r) {
            labels[v as usize] = 0;
            level[v as usize] = level[v as usize].abs();
        }
    }
    // Measurement noise, isotropic per vertex.
    if rough.noise > 0.0 {
        for p in &mut mesh.positions {
            *p += DVec3::new(
                rng.normal_clamped(2.5),
                rng.normal_clamped(2.5),
                rng.normal_clamped(2.5),
            ) * rough.noise;
        }
    }
    if rough.clip_margin {
        clip_labels(mesh, labels, &level);
    }
    unpinch(mesh, labels, 8);
    for _ in 0..rough.subdivisions {
        subdivide(mesh, labels);
    }
}

/// Relabels gingiva (0) the crown vertices where a crown's faces meet only at that vertex (the
/// label noise can leave such pinches), until every crown is manifold or `rounds` are spent:
/// islands and holes stay, pinches do not.
fn unpinch(mesh: &TriMesh, labels: &mut [i32], rounds: usize) {
    for _ in 0..rounds {
        let Ok(parts) = crate::mesh::split_by_vertex_labels(mesh, labels) else {
            return;
        };
        let mut pins = Vec::new();
        for s in parts.values().filter(|s| s.label != 0) {
            pins.extend(
                crate::mesh::non_manifold_vertices(&s.mesh)
                    .into_iter()
                    .map(|v| s.source_vertex[v as usize]),
            );
        }
        if pins.is_empty() {
            return;
        }
        for v in pins {
            labels[v as usize] = 0;
        }
    }
}

/// The tooth label of a vertex put on the edge between two differently labelled vertices:
/// the tooth's where one side is gingiva, else the lower-indexed end's.
fn cut_label(la: i32, lb: i32) -> i32 {
    if la == 0 { lb } else { la }
}

/// Cuts every edge whose ends carry different labels at the zero of the labelling level
/// (linear between its ends; the middle where their signs do not disagree), clamped to
/// [0.01, 0.99] of the edge, and re-triangulates the faces around the new vertices.
pub fn clip_labels(mesh: &mut TriMesh, labels: &mut Vec<i32>, level: &[f64]) {
    let mut cut: HashMap<(u32, u32), u32> = HashMap::new();
    let mut out = Vec::with_capacity(mesh.triangles.len() + mesh.triangles.len() / 8);
    let tris = std::mem::take(&mut mesh.triangles);
    for t in tris {
        let l = t.map(|v| labels[v as usize]);
        if l[0] == l[1] && l[1] == l[2] {
            out.push(t);
            continue;
        }
        let mut on_edge = |a: u32, b: u32| -> u32 {
            let key = (a.min(b), a.max(b));
            if let Some(&v) = cut.get(&key) {
                return v;
            }
            let (lo, hi) = (key.0 as usize, key.1 as usize);
            let (sl, sh) = (level[lo], level[hi]);
            let s = if (labels[lo] == 0) != (labels[hi] == 0) && sl * sh < 0.0 {
                (sl / (sl - sh)).clamp(0.01, 0.99)
            } else {
                0.5
            };
            let p = mesh.positions[lo].lerp(mesh.positions[hi], s);
            let v = mesh.positions.len() as u32;
            mesh.positions.push(p);
            labels.push(cut_label(labels[lo], labels[hi]));
            cut.insert(key, v);
            v
        };
        let odd = (0..3).find(|&k| l[(k + 1) % 3] == l[(k + 2) % 3]);
        match odd {
            Some(k) => {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let p = on_edge(a, b);
                let q = on_edge(a, c);
                out.push([a, p, q]);
                let pos = &mesh.positions;
                let d_pc = (pos[p as usize] - pos[c as usize]).length_squared();
                let d_bq = (pos[b as usize] - pos[q as usize]).length_squared();
                if d_pc <= d_bq {
                    out.push([p, b, c]);
                    out.push([p, c, q]);
                } else {
                    out.push([p, b, q]);
                    out.push([b, c, q]);
                }
            }
            None => {
                let [a, b, c] = t;
                let (ab, bc, ca) = (on_edge(a, b), on_edge(b, c), on_edge(c, a));
                out.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
        }
    }
    mesh.triangles = out;
}

/// One midpoint subdivision: every face into four; a midpoint carries its edge's label where
/// both ends agree, else the gingiva's (0).
pub fn subdivide(mesh: &mut TriMesh, labels: &mut Vec<i32>) {
    let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangles.len() * 2);
    let tris = std::mem::take(&mut mesh.triangles);
    let mut out = Vec::with_capacity(tris.len() * 4);
    for t in tris {
        let mut m = |a: u32, b: u32| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let v = mesh.positions.len() as u32;
                mesh.positions
                    .push(0.5 * (mesh.positions[a as usize] + mesh.positions[b as usize]));
                let (la, lb) = (labels[a as usize], labels[b as usize]);
                labels.push(if la == lb { la } else { 0 });
                v
            })
        };
        let [a, b, c] = t;
        let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
        out.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    mesh.triangles = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> (TriMesh, Vec<i32>) {
        let m = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        (m, vec![11, 0, 0, 0])
    }

    #[test]
    fn clipping_cuts_the_label_boundary_with_shared_vertices() {
        let (mut m, mut labels) = square();
        let level = vec![-0.1, 0.9, 0.9, 0.1];
        clip_labels(&mut m, &mut labels, &level);
        // Three cut edges (0-1, 0-2, 0-3), each one new vertex shared by its two faces.
        assert_eq!(m.positions.len(), 7);
        assert_eq!(m.triangles.len(), 6);
        assert_eq!(&labels[4..], &[11, 11, 11]);
        // The cut on 0-1 lies at the zero of the level: 0.1 of the way.
        assert!((m.positions[4] - DVec3::new(0.1, 0.0, 0.0)).length() < 1e-12);
        // Area and orientation kept; the crown is the corner at vertex 0.
        let area = |m: &TriMesh| -> DVec3 {
            m.triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|v| m.positions[v as usize]);
                    0.5 * (b - a).cross(c - a)
                })
                .sum()
        };
        assert!((area(&m) - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-12);
        let crown = m
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&v| labels[v as usize] == 11))
            .count();
        assert_eq!(crown, 2);
        assert_eq!(m.topology_report().boundary_loops, 1);
    }

    #[test]
    fn subdivision_quadruples_faces_and_keeps_labels_inside() {
        let (mut m, _) = square();
        let mut labels = vec![5, 5, 5, 0];
        subdivide(&mut m, &mut labels);
        assert_eq!(m.triangles.len(), 8);
        assert_eq!(m.positions.len(), 9);
        let r = m.topology_report();
        assert_eq!((r.components, r.boundary_loops), (1, 1));
        // Midpoints of 0-1, 1-2 and 0-2 are tooth 5; those touching vertex 3 are gingiva.
        assert_eq!(labels.iter().filter(|&&l| l == 5).count(), 6);
    }

    #[test]
    fn export_names_round_trip() {
        for e in IosExport::ALL {
            assert_eq!(IosExport::from_name(e.name()), Some(e));
        }
        assert!(IosExport::Clean.roughness().is_none());
        assert!(IosExport::ROUGH.iter().all(|e| e.roughness().is_some()));
    }
}
