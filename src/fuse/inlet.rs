//! Narrow inlets of the crown's margin. A segmentation tool's label boundary, or a notch the
//! scanner could not see into, can leave a slit in the crown: the margin runs from the gingival
//! edge up into the crown and back beside itself, a fraction of a millimetre apart. No band laid
//! from such a margin down to the root can avoid the crown wall below the slit, so before the
//! band is built each narrow inlet is closed: its two sides are zipped together by a strip of
//! faces on the existing vertices (no vertex moves, none is added), and the margin runs straight
//! across its mouth. An inlet is closed only when the strip crosses no crown face and adds no
//! edge the crown already has; every other inlet is left to the fringe trim and the band.

use super::band_crossings::overlap;
use crate::mesh::{EdgeTopology, TriMesh, boundary_loops};
use crate::mesh_check::{TriangleGrid, face_box, triangles_intersect};
use glam::DVec3;

/// Widest inlet mouth (mm) closed: a slit, far narrower than an interproximal notch the band
/// can follow (1.1-1.8 mm across).
const MOUTH_MM: f64 = 0.6;
/// Shortest inlet (mm along the margin, mouth to mouth) closed: shorter dents are the margin's
/// own raggedness, which the fringe trim handles.
const MIN_LENGTH_MM: f64 = 1.5;
/// An inlet runs along the margin at least this many times its mouth's width.
const SLENDERNESS: f64 = 4.0;
/// Inlets closed per crown at most.
const MAX_INLETS: usize = 8;

/// What [`close_inlets`] closed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InletReport {
    /// Inlets closed.
    pub closed: usize,
    /// Faces added (the strips).
    pub faces: usize,
    /// Margin length (mm) the closed inlets took out of the margin.
    pub length_mm: f64,
}

/// Closes the narrow inlets of `crown`'s margin (its single boundary loop; a crown with
/// another number of loops is left as it is), longest first. Returns what was closed.
pub fn close_inlets(crown: &mut TriMesh) -> InletReport {
    let mut report = InletReport::default();
    for _ in 0..MAX_INLETS {
        let loops = boundary_loops(crown);
        if loops.len() != 1 {
            break;
        }
        let lp = &loops[0];
        let candidates = inlets(crown, lp);
        if candidates.is_empty() {
            break;
        }
        let topo = EdgeTopology::new(crown);
        // The crown does not change while candidate strips are tested against it: its faces
        // are binned once, when a first strip gets as far as the crossing test.
        let mut near = None;
        let closed = candidates.into_iter().find_map(|(i, j, len)| {
            zip(crown, &topo, &mut near, lp, i, j).map(|faces| (faces, len))
        });
        let Some((faces, len)) = closed else {
            break;
        };
        report.closed += 1;
        report.faces += faces.len();
        report.length_mm += len;
        crown.triangles.extend(faces);
    }
    report
}

/// Candidate inlets of the loop `lp` as (mouth start, mouth end, length along the loop):
/// loop positions `i` and `j` (`j` after `i`, cyclically) whose mouth is at most [`MOUTH_MM`]
/// wide while the loop between them runs at least [`MIN_LENGTH_MM`] and [`SLENDERNESS`] times
/// the mouth, and at most half the loop. Longest first (then by position).
fn inlets(crown: &TriMesh, lp: &[u32]) -> Vec<(usize, usize, f64)> {
    let n = lp.len();
    let p = |k: usize| crown.positions[lp[k % n] as usize];
    let mut arc = vec![0.0; 2 * n + 1];
    for k in 0..2 * n {
        arc[k + 1] = arc[k] + (p(k + 1) - p(k)).length();
    }
    let total = arc[n];
    let mut out = Vec::new();
    for i in 0..n {
        let pi = p(i);
        for d in 2..n {
            let len = arc[i + d] - arc[i];
            if len > 0.5 * total {
                break;
            }
            let mouth = (p(i + d) - pi).length();
            if mouth <= MOUTH_MM && len >= MIN_LENGTH_MM && len >= SLENDERNESS * mouth {
                out.push((i, (i + d) % n, len));
            }
        }
    }
    out.sort_by(|a, b| b.2.total_cmp(&a.2).then((a.0, a.1).cmp(&(b.0, b.1))));
    out
}

/// The crown's faces binned on a grid, with their boxes: what a strip is tested against.
struct CrownFaces {
    grid: TriangleGrid,
    boxes: Vec<(DVec3, DVec3)>,
}

impl CrownFaces {
    fn new(crown: &TriMesh) -> CrownFaces {
        CrownFaces {
            grid: TriangleGrid::new(crown, 0.0),
            boxes: (0..crown.triangles.len())
                .map(|f| face_box(crown, f))
                .collect(),
        }
    }
}

/// Whether a face of `strip` (faces of `crown` appended after the faces `near` holds) crosses a
/// crown face or another strip face (exact test; the pairs whose boxes overlap, as
/// [`crate::mesh_check::crossing_pairs`] of the strip tests them).
fn strip_crosses(crown: &TriMesh, strip: std::ops::Range<usize>, near: &CrownFaces) -> bool {
    let boxes: Vec<(DVec3, DVec3)> = strip.clone().map(|f| face_box(crown, f)).collect();
    let mut around = Vec::new();
    for (k, f) in strip.clone().enumerate() {
        around.clear();
        near.grid
            .for_each_in_box(boxes[k].0, boxes[k].1, |g| around.push(g));
        around.sort_unstable();
        around.dedup();
        let crosses_crown = around.iter().any(|&g| {
            overlap(boxes[k], near.boxes[g as usize]) && triangles_intersect(crown, f, g as usize)
        });
        let crosses_strip = strip
            .clone()
            .enumerate()
            .skip(k + 1)
            .any(|(j, g)| overlap(boxes[k], boxes[j]) && triangles_intersect(crown, f, g));
        if crosses_crown || crosses_strip {
            return true;
        }
    }
    false
}

/// The strip closing the inlet of loop `lp` from position `i` to `j`: the two sides zipped from
/// the mouth inwards, each step advancing the side whose next diagonal is shorter. `None` when
/// the loop passes one of the inlet's vertices twice, a diagonal is already an edge of the
/// crown, or a strip face crosses the crown (or another strip face). The crown is left as it
/// was (the strip is appended to test it, then removed); `near` holds the crown's faces binned,
/// made here on first need.
fn zip(
    crown: &mut TriMesh,
    topo: &EdgeTopology,
    near: &mut Option<CrownFaces>,
    lp: &[u32],
    i: usize,
    j: usize,
) -> Option<Vec<[u32; 3]>> {
    let n = lp.len();
    let side: Vec<u32> = (0..=(j + n - i) % n).map(|k| lp[(i + k) % n]).collect();
    // Each of the inlet's vertices on the loop once: a vertex the loop passes twice (a pinch)
    // would keep a boundary fan on the other pass, and closing the strip around it would leave
    // it non-manifold.
    let mut seen = lp.to_vec();
    seen.sort_unstable();
    if side
        .iter()
        .any(|v| seen.partition_point(|w| w < v) + 1 != seen.partition_point(|w| w <= v))
    {
        return None;
    }
    let positions = &crown.positions;
    let at = |v: u32| positions[v as usize];
    let (mut a, mut b) = (0usize, side.len() - 1);
    let mut faces = Vec::with_capacity(side.len() - 2);
    // The loop runs a → a+1 along crown faces: a strip face uses each loop edge reversed.
    while b > a + 1 {
        let advance_a = b - a == 2 || {
            let da = (at(side[a + 1]) - at(side[b])).length();
            let db = (at(side[a]) - at(side[b - 1])).length();
            da <= db
        };
        let (face, diag) = if advance_a {
            a += 1;
            ([side[a], side[a - 1], side[b]], (side[a], side[b]))
        } else {
            b -= 1;
            ([side[b + 1], side[b], side[a]], (side[a], side[b]))
        };
        if b > a + 1 && topo.edge_face_count(diag.0, diag.1) > 0 {
            return None;
        }
        if faces.is_empty() && topo.edge_face_count(side[0], side[side.len() - 1]) > 0 {
            return None;
        }
        faces.push(face);
    }
    let degenerate = faces.iter().any(|t| {
        let [p, q, r] = t.map(at);
        (q - p).cross(r - p).length_squared() <= f64::EPSILON * (q - p).length_squared().max(1e-30)
    });
    if degenerate {
        return None;
    }
    // The strip is tested in place: appended to the crown, then taken off again.
    let near = near.get_or_insert_with(|| CrownFaces::new(crown));
    let first = crown.triangles.len();
    crown.triangles.extend_from_slice(&faces);
    let crossed = strip_crosses(crown, first..crown.triangles.len(), near);
    crown.triangles.truncate(first);
    (!crossed).then_some(faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A flat annulus-like disk with a slit: a square grid of `n`×`n` vertices (spacing `h`,
    /// in the z = 0 plane) with the faces of one column of cells removed from the bottom edge up
    /// `depth` cells, the two sides of the removed column `h` apart.
    fn slit_grid(n: usize, h: f64, col: usize, depth: usize) -> TriMesh {
        let mut pos = Vec::new();
        for y in 0..n {
            for x in 0..n {
                pos.push(DVec3::new(x as f64 * h, y as f64 * h, 0.0));
            }
        }
        let id = |x: usize, y: usize| (y * n + x) as u32;
        let mut tris = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                if x == col && y < depth {
                    continue;
                }
                tris.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                tris.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
        TriMesh::new(pos, tris)
    }

    fn loop_length(m: &TriMesh) -> f64 {
        let l = &boundary_loops(m)[0];
        (0..l.len())
            .map(|k| {
                (m.positions[l[k] as usize] - m.positions[l[(k + 1) % l.len()] as usize]).length()
            })
            .sum()
    }

    /// The strip test on the crown's binned faces answers as the search of every face does
    /// (`crossing_pairs` of the strip), on random strips over a jittered grid: strips of 1-6
    /// faces on vertices floating over it and on its own vertices, some crossing it or each
    /// other, some clear.
    #[test]
    fn a_strip_crosses_the_binned_crown_exactly_when_the_full_search_says_so() {
        let mut rng = crate::phantom::rng::Rng::new(11);
        let mut m = slit_grid(14, 0.25, 6, 7);
        for p in &mut m.positions {
            *p += DVec3::new(0.0, 0.0, rng.range(-0.12, 0.12));
        }
        let on_grid = m.positions.len();
        for _ in 0..80 {
            let (x, y) = (rng.range(0.0, 3.25), rng.range(0.0, 3.25));
            m.positions.push(DVec3::new(x, y, rng.range(0.15, 0.5)));
        }
        let near = CrownFaces::new(&m);
        let (mut crossing, mut clear) = (0, 0);
        for _ in 0..600 {
            let first = m.triangles.len();
            for _ in 0..1 + rng.below(6) {
                let mut pick = || {
                    if rng.below(4) == 0 {
                        rng.below(on_grid) as u32
                    } else {
                        (on_grid + rng.below(80)) as u32
                    }
                };
                let t = [pick(), pick(), pick()];
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    m.triangles.push(t);
                }
            }
            let strip: Vec<u32> = (first as u32..m.triangles.len() as u32).collect();
            let full = !crate::mesh_check::crossing_pairs(&m, &strip).is_empty();
            assert_eq!(strip_crosses(&m, first..m.triangles.len(), &near), full);
            if full {
                crossing += 1;
            } else if !strip.is_empty() {
                clear += 1;
            }
            m.triangles.truncate(first);
        }
        assert!(
            crossing > 50 && clear > 50,
            "{crossing} crossing, {clear} clear"
        );
    }

    #[test]
    fn a_slit_is_zipped_shut_and_the_margin_runs_across_its_mouth() {
        let mut m = slit_grid(12, 0.25, 5, 8);
        let (faces, before) = (m.triangles.len(), loop_length(&m));
        let r = close_inlets(&mut m);
        assert_eq!(r.closed, 1);
        // The slit's sides have 9 vertices each: 18 vertices, 16 strip faces.
        assert_eq!(r.faces, 16);
        assert_eq!(m.triangles.len(), faces + 16);
        let loops = boundary_loops(&m);
        assert_eq!(loops.len(), 1);
        assert!((before - loop_length(&m) - (r.length_mm - 0.25)).abs() < 1e-9);
        // Closed: exactly the square's outline is left.
        assert!((loop_length(&m) - 4.0 * 11.0 * 0.25).abs() < 1e-9);
        let topo = EdgeTopology::new(&m);
        let (boundary, non_manifold) = topo.edge_counts();
        assert_eq!((boundary, non_manifold), (44, 0));
        assert!(crate::mesh_check::self_intersections(&m).is_empty());
    }

    #[test]
    fn a_wide_notch_and_a_short_dent_stay_open() {
        // Mouth 0.75 mm: wider than a slit.
        let mut wide = slit_grid(12, 0.75, 5, 8);
        assert_eq!(close_inlets(&mut wide), InletReport::default());
        // Length 2 x 0.25 + 0.25 < 1.5 mm.
        let mut dent = slit_grid(12, 0.25, 5, 1);
        assert_eq!(close_inlets(&mut dent), InletReport::default());
    }

    #[test]
    fn a_slit_whose_strip_would_cross_the_crown_stays_open() {
        // Two crown vertices left of the slit pulled over it, one above and one below its
        // plane: the face between them pierces the slit's plane inside the slit.
        let (n, h, col) = (12, 0.25, 5);
        let mut m = slit_grid(n, h, col, 8);
        m.positions[4 * n + col - 1] = DVec3::new((col as f64 + 0.3) * h, 4.0 * h, 0.3 * h);
        m.positions[5 * n + col - 1] = DVec3::new((col as f64 + 0.3) * h, 5.0 * h, -0.3 * h);
        let before = m.clone();
        let own = crate::mesh_check::self_intersections(&before);
        assert!(!own.is_empty());
        let r = close_inlets(&mut m);
        // Only the slit's inner part, above the pierced rows, is closed: the margin crosses the
        // slit there, and the strip adds no crossing.
        let whole = 2.0 * 8.0 * h + h;
        assert_eq!(r.closed, 1);
        assert!(r.length_mm < whole - 4.0 * h, "{r:?}");
        assert_eq!(m.triangles[..before.triangles.len()], before.triangles[..]);
        assert_eq!(crate::mesh_check::self_intersections(&m), own);
    }

    #[test]
    fn a_slit_pinched_to_a_hole_leaves_no_vertex_non_manifold() {
        // One face beside the slit removed: a triangular hole touching the slit's side at one
        // vertex, so the margin may pass that vertex twice. Whatever is closed, no edge or vertex
        // becomes non-manifold and no crossing is added.
        let (n, h, col) = (12, 0.25, 5);
        let mut m = slit_grid(n, h, col, 8);
        let id = |x: usize, y: usize| (y * n + x) as u32;
        let gone = [id(col - 1, 4), id(col, 5), id(col - 1, 5)];
        let before = m.triangles.len();
        m.triangles.retain(|t| *t != gone);
        assert_eq!(m.triangles.len(), before - 1);
        let was = m.topology_report();
        let r = close_inlets(&mut m);
        let now = m.topology_report();
        assert_eq!(now.non_manifold_edges, 0, "{r:?}");
        assert!(
            now.non_manifold_vertices <= was.non_manifold_vertices,
            "{was:?} -> {now:?}"
        );
        assert!(crate::mesh_check::self_intersections(&m).is_empty());
    }

    #[test]
    fn an_inlet_whose_loop_passes_one_of_its_vertices_twice_is_not_zipped() {
        let mut m = slit_grid(12, 0.25, 5, 8);
        let lp = boundary_loops(&m)[0].clone();
        let topo = EdgeTopology::new(&m);
        let before = m.clone();
        // The inlet close_inlets zips: the first candidate whose strip is valid.
        let (i, j, _) = inlets(&m, &lp)
            .into_iter()
            .find(|&(i, j, _)| zip(&mut m, &topo, &mut None, &lp, i, j).is_some())
            .expect("the slit can be zipped");
        assert_eq!(m, before, "the crown is left as it was");
        // The same loop passing the slit's innermost vertex once more away from the slit, as a
        // loop pinched at that vertex does: the strip alone would be valid (it is the one above),
        // but closing it would leave the vertex's other boundary fan open beside it.
        let n = lp.len();
        let inner = lp[(i + ((j + n - i) % n) / 2) % n];
        let away = (j + (n - (j + n - i) % n) / 2) % n;
        let mut pinched = lp.clone();
        pinched.insert(away + 1, inner);
        let pos = |v: u32| pinched.iter().position(|&w| w == v).unwrap();
        let (pi, pj) = (pos(lp[i]), pos(lp[j]));
        assert_eq!(
            (pj + pinched.len() - pi) % pinched.len(),
            (j + n - i) % n,
            "the inlet's side is the same"
        );
        assert!(zip(&mut m, &topo, &mut None, &pinched, pi, pj).is_none());
        assert_eq!(m, before);
    }
}
