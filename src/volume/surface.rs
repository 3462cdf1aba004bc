//! Label → closed tooth mesh: the label's occupancy in its bounding box (padded), cavities
//! filled, a binomial partial-volume blur, surface nets at the 0.5 level (after making the
//! inside well-composed), the largest component, mapped to world millimetres by the volume's
//! affine (faces flipped when the affine mirrors, so normals point outward).

use super::{LabelVolume, VolumeScheme};
use crate::mesh::TriMesh;
use crate::phantom::{Grid, extract_closed};
use crate::{Error, Result};
use glam::{DMat3, DVec3};
use std::collections::BTreeMap;

/// Options of [`surface_teeth`].
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceOptions {
    /// Passes of the [1 2 1]/4 blur along each axis over the occupancy (0 = the staircase
    /// of the raw mask). One pass keeps a flat boundary at the mid-point between voxel centres.
    pub smoothing_passes: usize,
    /// Labels with less volume than this (mm³) are fragments, not teeth: skipped and named.
    pub min_volume_mm3: f64,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions {
            smoothing_passes: 1,
            min_volume_mm3: 20.0,
        }
    }
}

/// One tooth surfaced from a label volume.
#[derive(Clone, Debug)]
pub struct SurfacedTooth {
    /// The label value in the volume.
    pub label: u16,
    /// Closed, manifold, outward mesh in world millimetres (the volume's frame).
    pub mesh: TriMesh,
    /// Voxels carrying the label.
    pub voxels: usize,
    /// True when the label reaches the edge of the volume (the tooth is cut by the field of view).
    pub touches_border: bool,
}

/// The teeth of a per-tooth label volume, by FDI number, and the labels left out with why.
#[derive(Clone, Debug, Default)]
pub struct SurfacedTeeth {
    /// Surfaced teeth by FDI number.
    pub teeth: BTreeMap<u8, SurfacedTooth>,
    /// Labels not surfaced (non-tooth structures, fragments) with the reason.
    pub skipped: Vec<(u16, String)>,
}

/// Surfaces every tooth label of a per-tooth volume (`scheme` gives the FDI numbers). Errors
/// name a label the scheme does not know, two labels with one FDI number, or a volume without
/// tooth labels; a DentalSegmentator volume (one teeth label per jaw) is refused here. Under a
/// progress callback ([`crate::progress::with_progress`]) each label surfaced is a unit of
/// [`crate::progress::Stage::Surface`], and a cancel returns [`crate::Error::Cancelled`].
pub fn surface_teeth(
    vol: &LabelVolume,
    scheme: VolumeScheme,
    opts: &SurfaceOptions,
) -> Result<SurfacedTeeth> {
    if !scheme.is_per_tooth() {
        return Err(Error::InvalidArgument(
            "this volume has one teeth label per jaw (DentalSegmentator classes): its teeth must \
             be split with the IOS first"
                .into(),
        ));
    }
    let counts = vol.label_counts();
    let labels: Vec<u16> = counts.keys().copied().collect();
    // Under Universal numbering 1-5 are teeth; elsewhere they are DentalSegmentator's classes.
    if scheme != VolumeScheme::Universal && super::numbering::looks_like_dentalsegmentator(&labels)
    {
        return Err(Error::InvalidArgument(format!(
            "the volume's labels {labels:?} look like DentalSegmentator classes (3 upper teeth, \
             4 lower teeth), not one label per tooth: read it with the dentalsegmentator classes"
        )));
    }
    let boxes = vol.label_boxes();
    let voxel_mm3 = DMat3::from_mat4(vol.voxel_to_world).determinant().abs();
    let mut out = SurfacedTeeth::default();
    let mut work = Vec::new();
    for (&label, &count) in &counts {
        let Some(fdi) = scheme.tooth_fdi(label)? else {
            out.skipped
                .push((label, "not a tooth in this numbering".into()));
            continue;
        };
        let volume = count as f64 * voxel_mm3;
        if volume < opts.min_volume_mm3 {
            out.skipped.push((
                label,
                format!(
                    "fragment: {count} voxels = {volume:.1} mm^3 (< {} mm^3)",
                    opts.min_volume_mm3
                ),
            ));
            continue;
        }
        if let Some(prev) = work.iter().find(|w: &&(u8, u16, usize)| w.0 == fdi) {
            return Err(Error::InvalidArgument(format!(
                "volume labels {} and {label} are both FDI tooth {fdi}",
                prev.1
            )));
        }
        work.push((fdi, label, count));
    }
    if work.is_empty() {
        return Err(Error::MissingData(format!(
            "the label volume holds no tooth label ({} label(s) present: {labels:?})",
            labels.len()
        )));
    }
    use crate::progress::{Stage, check, ended, start, unit};
    start(Stage::Surface, work.len());
    let meshes = crate::par::map_ordered(&work, |&(_, label, _)| {
        let (lo, hi) = boxes[&label];
        unit(Stage::Surface, || {
            surface_box(vol, lo, hi, opts.smoothing_passes, |l| l == label)
        })
    });
    ended();
    check(Stage::Surface)?;
    for ((fdi, label, count), mesh) in work.into_iter().zip(meshes) {
        let (lo, hi) = boxes[&label];
        let touches_border = (0..3).any(|a| lo[a] == 0 || hi[a] + 1 == vol.dims[a]);
        let mesh = mesh.map_err(|e| Error::InvalidArgument(format!("label {label}: {e}")))?;
        out.teeth.insert(
            fdi,
            SurfacedTooth {
                label,
                mesh,
                voxels: count,
                touches_border,
            },
        );
    }
    Ok(out)
}

/// The closed surface of label `label` (see the module doc), in world millimetres.
pub fn surface_label(vol: &LabelVolume, label: u16, smoothing_passes: usize) -> Result<TriMesh> {
    let boxes = vol.label_boxes();
    let Some(&(lo, hi)) = boxes.get(&label) else {
        return Err(Error::MissingData(format!(
            "label {label} is not in the volume"
        )));
    };
    surface_box(vol, lo, hi, smoothing_passes, |l| l == label)
}

/// Surfaces the voxels `inside(label)` within the inclusive box `lo..=hi`.
pub(crate) fn surface_box(
    vol: &LabelVolume,
    lo: [usize; 3],
    hi: [usize; 3],
    smoothing_passes: usize,
    inside: impl Fn(u16) -> bool,
) -> Result<TriMesh> {
    let pad = 2 + smoothing_passes;
    let dims: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a] + 1 + 2 * pad);
    let mut occ = vec![0f32; dims[0] * dims[1] * dims[2]];
    let gid = |i: usize, j: usize, k: usize| i + dims[0] * (j + dims[1] * k);
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            let row = vol.idx(0, j, k);
            for i in lo[0]..=hi[0] {
                if inside(vol.labels[row + i]) {
                    occ[gid(i - lo[0] + pad, j - lo[1] + pad, k - lo[2] + pad)] = 1.0;
                }
            }
        }
    }
    fill_cavities(&mut occ, dims);
    for _ in 0..smoothing_passes {
        blur_121(&mut occ, dims);
    }
    let values = occ.iter().map(|&o| 0.5 - o).collect();
    let origin = DVec3::new(
        lo[0] as f64 - pad as f64,
        lo[1] as f64 - pad as f64,
        lo[2] as f64 - pad as f64,
    );
    let mut grid = Grid {
        origin,
        h: 1.0,
        dims,
        values,
    };
    grid.force_border_outside();
    let mut mesh = extract_closed(&mut grid);
    if mesh.face_count() == 0 {
        return Err(Error::MissingData(
            "no surface: the label is too thin (about 2 voxels or less across) to survive the \
             partial-volume smoothing"
                .into(),
        ));
    }
    for p in &mut mesh.positions {
        *p = vol.world(*p);
    }
    if DMat3::from_mat4(vol.voxel_to_world).determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(mesh)
}

/// Turns every background voxel not 6-connected to the box border into foreground (closed
/// cavities such as a pulp chamber the segmenter left out).
fn fill_cavities(occ: &mut [f32], dims: [usize; 3]) {
    let [nx, ny, nz] = dims;
    let mut seen = vec![false; occ.len()];
    let mut stack = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1 {
                    let id = i + nx * (j + ny * k);
                    if occ[id] == 0.0 && !seen[id] {
                        seen[id] = true;
                        stack.push(id);
                    }
                }
            }
        }
    }
    while let Some(id) = stack.pop() {
        let (i, j, k) = (id % nx, (id / nx) % ny, id / (nx * ny));
        let mut visit = |n: usize| {
            if occ[n] == 0.0 && !seen[n] {
                seen[n] = true;
                stack.push(n);
            }
        };
        if i > 0 {
            visit(id - 1);
        }
        if i + 1 < nx {
            visit(id + 1);
        }
        if j > 0 {
            visit(id - nx);
        }
        if j + 1 < ny {
            visit(id + nx);
        }
        if k > 0 {
            visit(id - nx * ny);
        }
        if k + 1 < nz {
            visit(id + nx * ny);
        }
    }
    for (o, s) in occ.iter_mut().zip(&seen) {
        if !*s {
            *o = 1.0;
        }
    }
}

/// One [1 2 1]/4 pass along each axis (values beyond the box taken as the edge value).
fn blur_121(v: &mut [f32], dims: [usize; 3]) {
    let strides = [1, dims[0], dims[0] * dims[1]];
    let mut tmp = v.to_vec();
    for a in 0..3 {
        let s = strides[a];
        let n = dims[a];
        for (id, out) in tmp.iter_mut().enumerate() {
            let c = (id / s) % n;
            let lo = if c > 0 { v[id - s] } else { v[id] };
            let hi = if c + 1 < n { v[id + s] } else { v[id] };
            *out = 0.25 * lo + 0.5 * v[id] + 0.25 * hi;
        }
        v.copy_from_slice(&tmp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ValidateOptions;
    use crate::volume::Frame;
    use glam::{DMat4, DVec4};

    /// A ball of radius `r` mm voxelised (voxel centres inside) on a grid with the given affine.
    fn ball(dims: [usize; 3], m: DMat4, centre: DVec3, r: f64) -> LabelVolume {
        let mut labels = vec![0u16; dims[0] * dims[1] * dims[2]];
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = m.transform_point3(DVec3::new(i as f64, j as f64, k as f64));
                    if (p - centre).length() < r {
                        labels[i + dims[0] * (j + dims[1] * k)] = 36;
                    }
                }
            }
        }
        LabelVolume::new(dims, m, Frame::Lps, labels).unwrap()
    }

    fn check_ball(vol: &LabelVolume, centre: DVec3, r: f64, tol: f64) {
        let t = surface_teeth(vol, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap();
        let m = &t.teeth[&36].mesh;
        let rep = m
            .validate(&ValidateOptions {
                require_closed: true,
                allow_zero_area: false,
            })
            .unwrap();
        assert!(rep.is_closed_manifold() && rep.components == 1);
        assert!(m.signed_volume() > 0.0, "outward");
        let worst = m
            .positions
            .iter()
            .map(|p| ((*p - centre).length() - r).abs())
            .fold(0.0, f64::max);
        assert!(worst < tol, "worst radial error {worst} mm");
    }

    #[test]
    fn ball_on_negative_anisotropic_and_oblique_grids() {
        let c = DVec3::new(10.0, -5.0, 3.0);
        let r = 3.0;
        // Axis-aligned, negative x and y spacing (LPS-style NIfTI), anisotropic.
        let h = [-0.25, -0.3, 0.4];
        let dims = [32, 28, 22];
        let o = c - DVec3::new(h[0] * 16.0, h[1] * 14.0, h[2] * 11.0);
        let m = DMat4::from_cols(
            DVec4::new(h[0], 0.0, 0.0, 0.0),
            DVec4::new(0.0, h[1], 0.0, 0.0),
            DVec4::new(0.0, 0.0, h[2], 0.0),
            o.extend(1.0),
        );
        check_ball(&ball(dims, m, c, r), c, r, 0.2);
        // Oblique: rotated 30° about z and 20° about x, 0.25 mm isotropic.
        let rot = DMat3::from_rotation_z(0.52) * DMat3::from_rotation_x(0.35) * 0.25;
        let dims = [36, 36, 36];
        let o = c - rot * DVec3::splat(18.0);
        let m = DMat4::from_mat3_translation(rot, o);
        check_ball(&ball(dims, m, c, r), c, r, 0.15);
    }

    #[test]
    fn cavity_filled_and_fragment_skipped() {
        let dims = [30, 30, 30];
        let m = DMat4::from_diagonal(DVec4::new(0.3, 0.3, 0.3, 1.0));
        let c = DVec3::splat(4.5);
        let mut v = ball(dims, m, c, 3.0);
        let hollow = ball(dims, m, c, 1.5);
        for (l, h) in v.labels.iter_mut().zip(&hollow.labels) {
            if *h != 0 {
                *l = 0;
            }
        }
        v.labels[0] = 11;
        let t = surface_teeth(&v, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap();
        assert_eq!(t.teeth.len(), 1);
        assert_eq!(t.skipped.len(), 1);
        assert_eq!(t.skipped[0].0, 11);
        let mesh = &t.teeth[&36].mesh;
        assert_eq!(mesh.topology_report().components, 1, "cavity removed");
        let vol = mesh.signed_volume();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 27.0;
        assert!((vol - exact).abs() / exact < 0.05, "{vol} vs {exact}");
    }

    #[test]
    fn per_jaw_and_unknown_labels_are_refused() {
        let m = DMat4::from_diagonal(DVec4::new(0.5, 0.5, 0.5, 1.0));
        let mut v = LabelVolume::new([4, 4, 4], m, Frame::Lps, vec![0; 64]).unwrap();
        v.labels[5] = 3;
        v.labels[6] = 4;
        let e = surface_teeth(&v, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap_err();
        assert!(e.to_string().contains("DentalSegmentator"), "{e}");
        // Under Universal numbering labels 3 and 4 are teeth (FDI 16 and 15), not jaw classes.
        let mut w = LabelVolume::new([10, 10, 10], m, Frame::Lps, vec![0; 1000]).unwrap();
        for k in 1..4 {
            for j in 1..4 {
                for i in 1..9 {
                    let id = w.idx(i, j, k);
                    w.labels[id] = if i < 5 { 3 } else { 4 };
                }
            }
        }
        let opts = SurfaceOptions {
            min_volume_mm3: 0.0,
            ..Default::default()
        };
        let u = surface_teeth(&w, VolumeScheme::Universal, &opts).unwrap();
        assert_eq!(u.teeth.keys().copied().collect::<Vec<_>>(), vec![15, 16]);
        assert!(surface_teeth(&w, VolumeScheme::Fdi, &opts).is_err());
        v.labels[6] = 99;
        let e = surface_teeth(&v, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap_err();
        assert!(e.to_string().contains("label 3 is not an FDI"), "{e}");
        let v0 = LabelVolume::new([4, 4, 4], m, Frame::Lps, vec![0; 64]).unwrap();
        let e = surface_teeth(&v0, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap_err();
        assert!(e.to_string().contains("no tooth label"), "{e}");
    }
}
