//! One tooth: IOS crown + CBCT tooth + their rigid transforms into the output frame → one closed,
//! manifold, outward-oriented mesh that holds every IOS crown vertex at exactly its transformed
//! position (paper section 2.3, Algorithm 1 line 2–7 for one tooth).

use super::FuseOptions;
use super::assembly::stitch_tooth;
use super::quality::ToothQuality;
use crate::cut::{self, RootCut, ToothFrame};
use crate::mesh::{RepairOptions, TriMesh, boundary_loops, repair_open_surface, sorted_corners};
use crate::stitch::{self, BandVertex};
use crate::{Error, Result, Rigid};
use glam::DVec3;

/// A fused tooth.
#[derive(Clone, Debug)]
pub struct FusedTooth {
    /// FDI number.
    pub fdi: u8,
    /// The fused closed mesh, output frame. Vertices: first the (repaired) IOS crown's, then the
    /// band interior, then the CBCT root.
    pub mesh: TriMesh,
    /// Per vertex: [`VertexSource`](super::VertexSource) as `u8` (0 IOS, 1 band or fill, 2 CBCT).
    pub source: Vec<u8>,
    /// Per vertex of `mesh`: the index of the IOS crown input vertex it is (its position is
    /// bitwise `ios_to_output.apply(input)`), or `u32::MAX` for band, fill and CBCT vertices.
    pub ios_vertex: Vec<u32>,
    /// Faces of `mesh`: the crown's first (`0..band_faces.start`), then the band's
    /// (`band_faces`), then the root's.
    pub band_faces: std::ops::Range<usize>,
    /// The crown faces (below `band_faces.start`, ascending) that are no face of the input
    /// crown: caps of holes the repair filled and strips closing slits at the margin (a cap
    /// face on the three corners of an input face, the face itself put back, counts as input).
    pub crown_faces_added: Vec<u32>,
    /// Quality report.
    pub quality: ToothQuality,
    /// Warnings (filled holes, flipped input orientation, self-intersections).
    pub warnings: Vec<String>,
    /// Time (ms) spent in crown removal (repair, frame, cut: [`CutTooth::cut_ms`]) and in
    /// stitching (band, assembly, flips, quality report) for this tooth.
    pub cut_ms: f64,
    /// See [`FusedTooth::cut_ms`].
    pub stitch_ms: f64,
    /// Band builds made for this tooth over every remedy (one for a crown whose first band
    /// crosses nothing; rough and foreign crowns take several: see the margin fringe in the
    /// README). How hard the tooth was, not a quality measure.
    pub band_builds: usize,
    /// Band builds a remedy asked for again with inputs an earlier build of this tooth had,
    /// bit for bit: that build reused, not made again (not counted in
    /// [`FusedTooth::band_builds`]). Only teeth whose remedies go round a cycle of trims have
    /// any.
    pub band_builds_reused: usize,
}

impl FusedTooth {
    /// Intersecting pairs of two kept IOS crown faces (exact test): the input crown's own
    /// crossings, kept as given. Counted on demand (an all-pairs check of the crown through a
    /// grid: ~10–20 ms for a crown of 15 000 faces), not during the fusion.
    pub fn ios_self_intersections(&self) -> usize {
        let crown = TriMesh::new(
            self.mesh.positions.clone(),
            self.mesh.triangles[..self.band_faces.start].to_vec(),
        );
        let added = |f: u32| self.crown_faces_added.binary_search(&f).is_ok();
        crate::mesh_check::self_intersections(&crown)
            .into_iter()
            .filter(|&(f, g)| !added(f) && !added(g))
            .count()
    }
}

/// The input crown's faces as sorted corner triples, sorted: a crown face is one of the input's
/// when its corners' input indices are found here.
pub(super) fn face_keys(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut keys: Vec<[u32; 3]> = triangles.iter().map(|&t| sorted_corners(t)).collect();
    keys.sort_unstable();
    keys
}

/// The faces among `crown` (vertices mapped to input indices by `ios_vertex`, `u32::MAX` for
/// none) that are no face of the input (`input_keys` from [`face_keys`]), ascending.
pub(super) fn faces_added(
    crown: &[[u32; 3]],
    ios_vertex: &[u32],
    input_keys: &[[u32; 3]],
) -> Vec<u32> {
    // The keys are sorted by their smallest corner: `first[v]..first[v + 1]` are the keys whose
    // smallest corner is `v` (a few), so a lookup scans those instead of searching them all.
    let n = input_keys.last().map_or(0, |k| k[0] as usize + 1);
    let mut first = vec![0u32; n + 1];
    for k in input_keys {
        first[k[0] as usize + 1] += 1;
    }
    for v in 0..n {
        first[v + 1] += first[v];
    }
    let is_input = |k: [u32; 3]| {
        let v = k[0] as usize;
        v < n && input_keys[first[v] as usize..first[v + 1] as usize].contains(&k)
    };
    (0..crown.len() as u32)
        .filter(|&f| {
            let k = sorted_corners(crown[f as usize].map(|v| ios_vertex[v as usize]));
            k[2] == u32::MAX || !is_input(k)
        })
        .collect()
}

/// A tooth after crown removal, before stitching ([`cut_tooth`] → [`stitch_tooth`]): the
/// repaired IOS crown and the cut CBCT root, both in the output frame, with everything the band
/// needs. Made only by [`cut_tooth`], so its loops always index its meshes.
#[derive(Clone, Debug)]
pub struct CutTooth {
    pub(super) fdi: u8,
    pub(super) crown: TriMesh,
    pub(super) margin: Vec<u32>,
    pub(super) crown_dirs: Vec<DVec3>,
    pub(super) frame: ToothFrame,
    pub(super) ios_vertex: Vec<u32>,
    /// The input crown's faces ([`face_keys`]).
    pub(super) input_faces: Vec<[u32; 3]>,
    pub(super) kept_ios: usize,
    pub(super) dropped: usize,
    pub(super) holes_filled: usize,
    pub(super) trimmed: super::fringe::FringeTrim,
    pub(super) dist_in: Vec<f64>,
    pub(super) root: RootCut,
    /// The whole CBCT tooth in the output frame, outward (the remedy that cuts again,
    /// [`super::flat_cut`], needs it; shared by the tooth's copies).
    pub(super) cbct: std::sync::Arc<TriMesh>,
    pub(super) root_dirs: Vec<DVec3>,
    pub(super) chords: Vec<(BandVertex, BandVertex)>,
    pub(super) warnings: Vec<String>,
    pub(super) cut_ms: f64,
}

impl CutTooth {
    /// FDI number.
    pub fn fdi(&self) -> u8 {
        self.fdi
    }

    /// The repaired IOS crown in the output frame, outward-oriented: an open disk whose one
    /// boundary loop is [`CutTooth::margin`]. It becomes the first vertices of the fused mesh.
    pub fn crown(&self) -> &TriMesh {
        &self.crown
    }

    /// The gingival margin: the crown's boundary loop (crown vertex indices, crown on the left
    /// seen from outside).
    pub fn margin(&self) -> &[u32] {
        &self.margin
    }

    /// Per crown vertex: the index of the IOS crown input vertex it is, or `u32::MAX` for a
    /// vertex added by the repair (hole fill).
    pub fn ios_vertex(&self) -> &[u32] {
        &self.ios_vertex
    }

    /// The tooth frame (axis root → crown) found from the margin.
    pub fn frame(&self) -> &ToothFrame {
        &self.frame
    }

    /// The cut: the CBCT root in the output frame (an open disk, CBCT positions under
    /// `cbct_to_output`), its vertices' CBCT input indices, its single boundary loop and the
    /// number of crown faces removed.
    pub fn root(&self) -> &RootCut {
        &self.root
    }

    /// The root's boundary loop (root vertex indices), where the band meets the root.
    pub fn cut_loop(&self) -> &[u32] {
        &self.root.cut_loop
    }

    /// IOS crown holes filled by the repair.
    pub fn holes_filled(&self) -> usize {
        self.holes_filled
    }

    /// Warnings of the cut stage (repair, flipped orientations, dropped vertices).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Time (ms) spent in this tooth's cut stage (repair, frame, cut, loop directions).
    pub fn cut_ms(&self) -> f64 {
        self.cut_ms
    }

    /// This tooth on another root `rc` of its CBCT tooth (cut otherwise, or peeled at the cut):
    /// the root's loop directions and chords made anew, the crown side as it is.
    pub(super) fn with_root(&self, rc: RootCut) -> CutTooth {
        CutTooth {
            root_dirs: loop_dirs(&rc.root, &rc.cut_loop, self.frame.axis),
            chords: self
                .crown_chords()
                .chain(loop_chords(&rc.root, &rc.cut_loop, BandVertex::Lower))
                .collect(),
            root: rc,
            ..self.clone()
        }
    }

    /// The chords of the crown's margin.
    pub(super) fn crown_chords(&self) -> impl Iterator<Item = (BandVertex, BandVertex)> + '_ {
        self.chords
            .iter()
            .copied()
            .filter(|c| matches!(c.0, BandVertex::Upper(_)))
    }

    /// The chords of the root's cut loop (the crown's are the crown side's).
    pub(super) fn root_chords(&self) -> impl Iterator<Item = (BandVertex, BandVertex)> + '_ {
        self.chords
            .iter()
            .copied()
            .filter(|c| matches!(c.0, BandVertex::Lower(_)))
    }
}

/// Unit surface directions across a loop: `normal × tangent`, signed to point along `+axis`.
pub(super) fn loop_dirs(mesh: &TriMesh, lp: &[u32], axis: DVec3) -> Vec<DVec3> {
    let normals = mesh.vertex_normals();
    let n = lp.len();
    (0..n)
        .map(|i| {
            let p = |k: usize| mesh.positions[lp[k] as usize];
            let t = (p((i + 1) % n) - p((i + n - 1) % n)).normalize_or_zero();
            let nv = normals[lp[i] as usize];
            let mut d = nv.cross(t).normalize_or_zero();
            if d.dot(axis) < 0.0 {
                d = -d;
            }
            if d == DVec3::ZERO { axis } else { d }
        })
        .collect()
}

/// Fuses one tooth. `ios_crown` (IOS frame) is an open crown whose longest boundary loop is the
/// gingival margin; it is repaired first ([`repair_open_surface`]: small holes filled, bow-ties
/// split, islands dropped). `cbct` (CBCT frame) must
/// be closed and manifold. Equals [`stitch_tooth`] of [`cut_tooth`], bit for bit.
pub fn fuse_tooth(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<FusedTooth> {
    let cut = cut_tooth(fdi, ios_crown, cbct, ios_to_output, cbct_to_output, opts)?;
    stitch_tooth(&cut, opts)
}

/// The crown-removal stage of [`fuse_tooth`] (paper section 2.3.1): repairs the IOS crown and
/// moves it into the output frame, finds its margin loop and the tooth frame, and cuts the CBCT
/// crown off along the margin (`opts.cut`), keeping the root. Errors name the tooth.
pub fn cut_tooth(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<CutTooth> {
    cut_inner(fdi, ios_crown, cbct, ios_to_output, cbct_to_output, opts)
        .map_err(|e| e.in_tooth(fdi))
}

fn cut_inner(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<CutTooth> {
    let t_start = std::time::Instant::now();
    let mut warnings = Vec::new();
    // Real crowns are messy: make the crown one oriented manifold disk, filling small holes
    // (every kept vertex keeps its exact position). Repaired in the output frame: whether a
    // hole's cap crosses the crown is decided exactly on the positions the fused mesh holds
    // (in another frame, rounding can make a face touching a cap at a shared corner cross it).
    let (crown, rep_src, rep) = repair_open_surface(
        &ios_crown.transformed(ios_to_output),
        &RepairOptions::default(),
    );
    if !rep.is_clean() {
        warnings.push(format!("IOS crown repaired: {rep:?}"));
    }
    let FoldTrimmed {
        mut crown,
        rep_src,
        trimmed,
        dist_in,
        loops,
    } = fold_trim(
        crown,
        rep_src,
        ios_crown.positions.len(),
        opts,
        &mut warnings,
    );
    let mut root_in = cbct.transformed(cbct_to_output);
    if root_in.signed_volume() < 0.0 {
        root_in.flip();
        warnings.push("CBCT tooth was inward-oriented; flipped".into());
    }
    let loops = loops.unwrap_or_else(|| boundary_loops(&crown));
    if loops.len() != 1 {
        return Err(Error::InvalidArgument(format!(
            "IOS crown has {} boundary loops after repair; exactly one (the gingival margin) is needed",
            loops.len()
        )));
    }
    let mut margin = loops.into_iter().next().unwrap_or_default();
    let crown_centroid = crate::geom::centroid(&crown.positions).unwrap_or(DVec3::ZERO);
    let frame = ToothFrame::from_margin(&margin_pts_of(&crown, &margin), crown_centroid)?;
    if outward(&frame, &mut crown, &mut margin) {
        warnings.push(FLIPPED.into());
    }
    let ios_vertex = rep_src;
    let kept_ios = ios_vertex.iter().filter(|&&s| s != u32::MAX).count();
    let dropped = ios_crown
        .positions
        .len()
        .saturating_sub(kept_ios + trimmed.vertices);
    if dropped > 0 {
        warnings.push(format!(
            "{dropped} IOS crown vertices dropped by the repair (islands, unused, or only on faces taken with a hole)"
        ));
    }
    // Crown removal.
    let margin_pts = margin_pts_of(&crown, &margin);
    let (frame, rc) = cut_root(
        &root_in,
        &margin_pts,
        frame,
        crown_centroid,
        opts,
        &mut warnings,
    )?;
    // Where the cut was made about the CBCT tooth's long axis instead (the margin's plane tilted
    // far off it), the crown's orientation is judged again about that axis: about the tilted
    // one the margin's winding can come out either way (a scalloped incisor's margin was read
    // as inward, its crown flipped against its root and the tooth lost).
    if outward(&frame, &mut crown, &mut margin) {
        match warnings.iter().position(|w| w == FLIPPED) {
            Some(i) => {
                warnings.remove(i);
            }
            None => warnings.push(FLIPPED.into()),
        }
    }
    let crown_dirs = loop_dirs(&crown, &margin, frame.axis);
    let root_dirs = loop_dirs(&rc.root, &rc.cut_loop, frame.axis);
    let chords = loop_chords(&crown, &margin, BandVertex::Upper)
        .into_iter()
        .chain(loop_chords(&rc.root, &rc.cut_loop, BandVertex::Lower))
        .collect::<Vec<_>>();
    let cut_ms = t_start.elapsed().as_secs_f64() * 1e3;
    Ok(CutTooth {
        fdi,
        crown,
        margin,
        crown_dirs,
        frame,
        ios_vertex,
        input_faces: face_keys(&ios_crown.triangles),
        kept_ios,
        dropped,
        holes_filled: rep.filled_holes,
        trimmed,
        dist_in,
        root: rc,
        cbct: std::sync::Arc::new(root_in),
        root_dirs,
        chords,
        warnings,
        cut_ms,
    })
}

/// What [`fold_trim`] returns.
struct FoldTrimmed {
    /// The crown, trimmed or as it came.
    crown: TriMesh,
    /// Per vertex of `crown`, its IOS input index.
    rep_src: Vec<u32>,
    /// What the trim took.
    trimmed: super::fringe::FringeTrim,
    /// Per input vertex, its distance from the margin along the crown (empty when off).
    dist_in: Vec<f64>,
    /// `crown`'s boundary loops where they were found and nothing was trimmed after.
    loops: Option<Vec<Vec<u32>>>,
}

/// The fringe trim before the first band build (default preset, `opts.fringe_reach_mm` > 0):
/// crown faces within the reach of the margin that cross other crown faces, peeled
/// ([`super::fringe::trim_fringe`]).
fn fold_trim(
    mut crown: TriMesh,
    mut rep_src: Vec<u32>,
    input_vertices: usize,
    opts: &FuseOptions,
    warnings: &mut Vec<String>,
) -> FoldTrimmed {
    let mut trimmed = super::fringe::FringeTrim::default();
    let mut dist_in = Vec::new();
    let mut known_loops = None;
    if opts.fringe_reach_mm > 0.0 {
        let loops = boundary_loops(&crown);
        if loops.len() == 1 {
            let d = super::fringe::edge_distance(
                &crown,
                &loops[0],
                opts.fringe_reach_mm * super::remedy::widest_reach_factor(),
            );
            dist_in = vec![f64::INFINITY; input_vertices];
            for (v, &s) in rep_src.iter().enumerate() {
                if s != u32::MAX {
                    dist_in[s as usize] = dist_in[s as usize].min(d[v]);
                }
            }
            if let Some((m, map, t)) = super::fringe::trim_fringe(
                &crown,
                &rep_src,
                &dist_in,
                opts.fringe_reach_mm,
                &[],
                super::fringe::Listed::Within,
            ) {
                crown = m;
                rep_src = map;
                trimmed = t;
                warnings.push(format!(
                    "{} IOS crown vertices ({} faces) trimmed from the margin fringe (folded over other crown faces; at most {:.2} mm from the margin)",
                    t.vertices, t.faces, t.max_reach_mm
                ));
                return FoldTrimmed {
                    crown,
                    rep_src,
                    trimmed,
                    dist_in,
                    loops: None,
                };
            }
        }
        known_loops = Some(loops);
    }
    FoldTrimmed {
        crown,
        rep_src,
        trimmed,
        dist_in,
        loops: known_loops,
    }
}

/// Crown removal along the margin `margin_pts` about `frame`'s axis; where that cut fails or
/// does not go once around the tooth, the cut is made again about the CBCT tooth's long axis
/// (kept when it does). Returns the frame used and the cut.
fn cut_root(
    root_in: &TriMesh,
    margin_pts: &[DVec3],
    frame: ToothFrame,
    crown_point: DVec3,
    opts: &FuseOptions,
    warnings: &mut Vec<String>,
) -> Result<(ToothFrame, RootCut)> {
    let first = cut::cut_crown(root_in, margin_pts, &frame, &opts.cut);
    if matches!(&first, Ok(rc) if winds_once(&frame, rc)) {
        return first.map(|rc| (frame, rc));
    }
    // The margin's best-fit plane normal is the tooth axis where the margin is a ring around the
    // tooth; a narrow, deeply scalloped or ragged margin can tilt it far off (a lower incisor
    // whose labelled crown reaches the incisal edge at a contact: 82°), and then the cut about
    // it fails or does not go around the tooth. Such a cut is made again about the CBCT tooth's
    // long axis, whatever the tilt (a tooth that cuts well keeps its margin frame: a molar's long
    // axis can lie across it; and a tooth whose cut fails has nothing to lose).
    if let Some(long_frame) = long_axis_frame(root_in, frame.center, crown_point)
        && let Ok(r) = cut::cut_crown(root_in, margin_pts, &long_frame, &opts.cut)
        && winds_once(&long_frame, &r)
    {
        // The angle between the two axes as lines (the margin frame's may point either way).
        let tilt = frame.axis.angle_between(long_frame.axis).to_degrees();
        let tilt = tilt.min(180.0 - tilt);
        let how = match &first {
            Ok(_) => "did not go around the tooth".to_string(),
            Err(e) => format!("failed ({e})"),
        };
        warnings.push(format!(
            "the margin's plane is tilted {tilt:.0}° from the CBCT tooth's long axis and the cut about it {how}: cut about the long axis"
        ));
        return Ok((long_frame, r));
    }
    first.map(|rc| (frame, rc))
}

/// The frame about the CBCT tooth's long axis (its vertices' principal axis) through `center`,
/// pointing from the tooth's middle toward `crown_point` (the IOS crown's centroid): the margin
/// frame's axis cannot give that direction where it lies across the tooth.
fn long_axis_frame(root_in: &TriMesh, center: DVec3, crown_point: DVec3) -> Option<ToothFrame> {
    let (mid, long) = crate::geom::principal_axis(&root_in.positions)?;
    let toward_crown = (crown_point - mid).dot(long);
    (toward_crown != 0.0 && toward_crown.is_finite())
        .then(|| ToothFrame::new(center, long * toward_crown.signum()))
}

/// Whether the root's cut loop goes once around the tooth axis (either way), as the band needs.
pub(super) fn winds_once(frame: &ToothFrame, rc: &RootCut) -> bool {
    let w = stitch::param::winding(frame, &margin_pts_of(&rc.root, &rc.cut_loop));
    stitch::param::once_around(w).is_some()
}

/// The warning of a crown found inward-oriented and flipped.
const FLIPPED: &str = "IOS crown was inward-oriented; flipped";

/// Makes `crown` lie to the left of its margin seen from outside (the margin counter-clockwise
/// about `frame`'s axis): where it does not, the crown is inward-oriented and is flipped, its
/// margin reversed (positions untouched). Whether it was flipped.
fn outward(frame: &ToothFrame, crown: &mut TriMesh, margin: &mut [u32]) -> bool {
    let flip = stitch::param::winding(frame, &margin_pts_of(crown, margin)) < 0.0;
    if flip {
        crown.flip();
        margin.reverse();
    }
    flip
}

pub(super) fn margin_pts_of(mesh: &TriMesh, margin: &[u32]) -> Vec<DVec3> {
    margin.iter().map(|&v| mesh.positions[v as usize]).collect()
}

/// Mesh edges joining two non-consecutive vertices of loop `lp`, as loop positions.
pub(super) fn loop_chords(
    mesh: &TriMesh,
    lp: &[u32],
    wrap: fn(u32) -> BandVertex,
) -> Vec<(BandVertex, BandVertex)> {
    let mut pos = vec![u32::MAX; mesh.positions.len()];
    for (k, &v) in lp.iter().enumerate() {
        pos[v as usize] = k as u32;
    }
    let n = lp.len() as u32;
    let mut out = Vec::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (pos[t[k] as usize], pos[t[(k + 1) % 3] as usize]);
            if a == u32::MAX || b == u32::MAX || a > b {
                continue;
            }
            if b - a != 1 && !(a == 0 && b == n - 1) {
                out.push((wrap(a), wrap(b)));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::rng::Rng;

    /// [`faces_added`] answers as a binary search of the sorted keys does, on random crowns
    /// drawn from a small vertex range (so many faces share a smallest corner), with repair
    /// vertices (`u32::MAX`) among them.
    #[test]
    fn added_faces_are_those_the_sorted_keys_lack() {
        let mut rng = Rng::new(3);
        for case in 0..300 {
            let n = 3 + rng.below(40) as u32;
            let face = |rng: &mut Rng| {
                let a = rng.below(n as usize) as u32;
                let b = (a + 1 + rng.below(n as usize - 1) as u32) % n;
                let mut c = rng.below(n as usize) as u32;
                while c == a || c == b {
                    c = (c + 1) % n;
                }
                [a, b, c]
            };
            let input: Vec<[u32; 3]> = (0..rng.below(60)).map(|_| face(&mut rng)).collect();
            let keys = face_keys(&input);
            // The crown: some input faces (turned), some others; its vertices map to input
            // vertices, a few to none.
            let mut crown: Vec<[u32; 3]> = Vec::new();
            for _ in 0..rng.below(60) {
                if !input.is_empty() && rng.below(2) == 0 {
                    let t = input[rng.below(input.len())];
                    crown.push([t[1], t[2], t[0]]);
                } else {
                    crown.push(face(&mut rng));
                }
            }
            let ios_vertex: Vec<u32> = (0..n)
                .map(|v| if rng.below(15) == 0 { u32::MAX } else { v })
                .collect();
            let expect: Vec<u32> = (0..crown.len() as u32)
                .filter(|&f| {
                    let k = sorted_corners(crown[f as usize].map(|v| ios_vertex[v as usize]));
                    k[2] == u32::MAX || keys.binary_search(&k).is_err()
                })
                .collect();
            assert_eq!(
                faces_added(&crown, &ios_vertex, &keys),
                expect,
                "case {case}"
            );
        }
    }
}
