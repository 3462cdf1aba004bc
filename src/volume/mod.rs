//! CBCT label volumes: a grid of integer labels (one per tooth, or one per jaw) with the 4×4
//! voxel-to-world matrix that places it in millimetres.
//!
//! The world frame is named explicitly ([`Frame`]): NIfTI's world is RAS+, NRRD's and DICOM's
//! usually LPS+. [`LabelVolume::to_frame`] converts, so the surfaced teeth land in the frame the
//! host expects. [`surface`] turns each label into a closed tooth mesh; [`numbering`] maps
//! label values to FDI numbers; [`split`] splits a per-jaw teeth mask into teeth with the IOS.

pub mod numbering;
pub mod split;
pub mod surface;

pub use numbering::VolumeScheme;
pub use split::{SplitOptions, SplitVolume, split_teeth};
pub use surface::{SurfaceOptions, SurfacedTeeth, SurfacedTooth, surface_label, surface_teeth};

use crate::{Error, Result};
use glam::{DMat3, DMat4, DVec3, DVec4};
use std::collections::BTreeMap;

/// The patient-based world frame of a volume's voxel-to-world matrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Frame {
    /// +x toward the patient's left, +y posterior, +z superior (DICOM, ITK, NRRD `left-posterior-superior`,
    /// 3D Slicer's files).
    #[default]
    Lps,
    /// +x toward the patient's right, +y anterior, +z superior (NIfTI's world, Slicer's scene).
    Ras,
}

impl Frame {
    /// `"lps"` or `"ras"` (case-insensitive).
    pub fn from_name(name: &str) -> Option<Frame> {
        match name.to_ascii_lowercase().as_str() {
            "lps" => Some(Frame::Lps),
            "ras" => Some(Frame::Ras),
            _ => None,
        }
    }

    /// `"LPS"` or `"RAS"`.
    pub fn name(self) -> &'static str {
        match self {
            Frame::Lps => "LPS",
            Frame::Ras => "RAS",
        }
    }
}

/// An integer label volume: `dims` voxels (x fastest), label 0 = background, placed in the
/// world by `voxel_to_world` (voxel index (i, j, k) of a voxel centre → millimetres in `frame`).
#[derive(Clone, Debug, PartialEq)]
pub struct LabelVolume {
    /// Voxels along i, j, k.
    pub dims: [usize; 3],
    /// Voxel index → world millimetres (affine: last row 0 0 0 1).
    pub voxel_to_world: DMat4,
    /// The frame `voxel_to_world` maps into.
    pub frame: Frame,
    /// Labels, i fastest then j then k; `dims[0] * dims[1] * dims[2]` of them.
    pub labels: Vec<u16>,
}

impl LabelVolume {
    /// A volume, checked: every dimension ≥ 1, one label per voxel, a finite affine with last
    /// row (0, 0, 0, 1) and an invertible 3×3 part whose voxel sizes are 1 µm to 10 mm (errors
    /// say which).
    pub fn new(
        dims: [usize; 3],
        voxel_to_world: DMat4,
        frame: Frame,
        labels: Vec<u16>,
    ) -> Result<LabelVolume> {
        if dims.contains(&0) {
            return Err(Error::InvalidArgument(format!(
                "label volume dimensions {dims:?}: every dimension must be at least 1"
            )));
        }
        let n = dims[0]
            .checked_mul(dims[1])
            .and_then(|v| v.checked_mul(dims[2]))
            .ok_or_else(|| {
                Error::InvalidArgument(format!("label volume dimensions {dims:?} overflow"))
            })?;
        if labels.len() != n {
            return Err(Error::InvalidArgument(format!(
                "label volume {dims:?} needs {n} labels, got {}",
                labels.len()
            )));
        }
        check_affine(&voxel_to_world)?;
        Ok(LabelVolume {
            dims,
            voxel_to_world,
            frame,
            labels,
        })
    }

    /// A volume with axis-aligned voxels of `spacing` mm (negative entries flip an axis) whose
    /// voxel (0, 0, 0) centre is at `origin`.
    pub fn with_spacing(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        frame: Frame,
        labels: Vec<u16>,
    ) -> Result<LabelVolume> {
        let m = DMat4::from_cols(
            DVec4::new(spacing[0], 0.0, 0.0, 0.0),
            DVec4::new(0.0, spacing[1], 0.0, 0.0),
            DVec4::new(0.0, 0.0, spacing[2], 0.0),
            DVec4::new(origin[0], origin[1], origin[2], 1.0),
        );
        LabelVolume::new(dims, m, frame, labels)
    }

    /// Linear index of voxel (i, j, k).
    #[inline]
    pub fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// World position (mm, in [`Self::frame`]) of a continuous voxel index.
    pub fn world(&self, ijk: DVec3) -> DVec3 {
        self.voxel_to_world.transform_point3(ijk)
    }

    /// Voxel size along i, j, k (mm): the lengths of the affine's columns.
    pub fn spacing(&self) -> [f64; 3] {
        let m = DMat3::from_mat4(self.voxel_to_world);
        [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()]
    }

    /// The volume expressed in `frame` (LPS ↔ RAS negates world x and y).
    pub fn to_frame(&self, frame: Frame) -> LabelVolume {
        let mut v = self.clone();
        if frame != self.frame {
            v.voxel_to_world =
                DMat4::from_diagonal(DVec4::new(-1.0, -1.0, 1.0, 1.0)) * v.voxel_to_world;
            v.frame = frame;
        }
        v
    }

    /// Anatomical axis codes of the voxel axes, like nibabel's `aff2axcodes`: for each of i, j,
    /// k, the patient direction its world axis mostly points to (e.g. `"LPS"`, `"RAS"`,
    /// `"LAI"`).
    pub fn axis_codes(&self) -> String {
        let m = DMat3::from_mat4(self.voxel_to_world);
        let pos = match self.frame {
            Frame::Lps => ['L', 'P', 'S'],
            Frame::Ras => ['R', 'A', 'S'],
        };
        let neg = match self.frame {
            Frame::Lps => ['R', 'A', 'I'],
            Frame::Ras => ['L', 'P', 'I'],
        };
        [m.x_axis, m.y_axis, m.z_axis]
            .iter()
            .map(|c| {
                let a = c.abs();
                let w = if a.x >= a.y && a.x >= a.z {
                    0
                } else if a.y >= a.z {
                    1
                } else {
                    2
                };
                if c[w] >= 0.0 { pos[w] } else { neg[w] }
            })
            .collect()
    }

    /// True when the voxel axes are not parallel to the world axes (beyond 1e-6 of a column's
    /// length).
    pub fn is_oblique(&self) -> bool {
        let m = DMat3::from_mat4(self.voxel_to_world);
        [m.x_axis, m.y_axis, m.z_axis].iter().any(|c| {
            let a = c.abs();
            let big = a.max_element();
            (a.x + a.y + a.z - big) > 1e-6 * big
        })
    }

    /// Voxel count per non-zero label, ascending by label.
    pub fn label_counts(&self) -> BTreeMap<u16, usize> {
        let mut hist = vec![0usize; 65536];
        for &l in &self.labels {
            hist[l as usize] += 1;
        }
        hist.iter()
            .enumerate()
            .skip(1)
            .filter(|&(_, &c)| c > 0)
            .map(|(l, &c)| (l as u16, c))
            .collect()
    }

    /// Inclusive voxel bounding box `(lo, hi)` of every non-zero label, ascending by label.
    pub fn label_boxes(&self) -> BTreeMap<u16, ([usize; 3], [usize; 3])> {
        let mut boxes: BTreeMap<u16, ([usize; 3], [usize; 3])> = BTreeMap::new();
        let [nx, ny, _] = self.dims;
        for (id, &l) in self.labels.iter().enumerate() {
            if l == 0 {
                continue;
            }
            let p = [id % nx, (id / nx) % ny, id / (nx * ny)];
            let b = boxes.entry(l).or_insert((p, p));
            for (a, &pa) in p.iter().enumerate() {
                b.0[a] = b.0[a].min(pa);
                b.1[a] = b.1[a].max(pa);
            }
        }
        boxes
    }

    /// The sub-volume of voxels `lo..=hi` (inclusive, clamped to the volume), with the affine
    /// moved so that every voxel keeps its world position.
    pub fn crop(&self, lo: [usize; 3], hi: [usize; 3]) -> LabelVolume {
        let hi: [usize; 3] = std::array::from_fn(|a| hi[a].min(self.dims[a] - 1));
        let lo: [usize; 3] = std::array::from_fn(|a| lo[a].min(hi[a]));
        let dims: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a] + 1);
        let mut labels = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                let row = self.idx(lo[0], j, k);
                labels.extend_from_slice(&self.labels[row..row + dims[0]]);
            }
        }
        let shift = DMat4::from_translation(DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64));
        LabelVolume {
            dims,
            voxel_to_world: self.voxel_to_world * shift,
            frame: self.frame,
            labels,
        }
    }

    /// The volume cropped to the bounding box of all non-zero labels (unchanged when it has
    /// none).
    pub fn cropped_to_labels(&self) -> LabelVolume {
        let boxes = self.label_boxes();
        let Some(first) = boxes.values().next() else {
            return self.clone();
        };
        let (mut lo, mut hi) = *first;
        for (l, h) in boxes.values() {
            for a in 0..3 {
                lo[a] = lo[a].min(l[a]);
                hi[a] = hi[a].max(h[a]);
            }
        }
        self.crop(lo, hi)
    }

    /// A copy with every label replaced by `map(label)` (0 = background).
    pub fn relabeled(&self, map: impl Fn(u16) -> u16) -> LabelVolume {
        let mut v = self.clone();
        for l in &mut v.labels {
            *l = map(*l);
        }
        v
    }
}

fn check_affine(m: &DMat4) -> Result<()> {
    let a = m.to_cols_array();
    if a.iter().any(|v| !v.is_finite()) {
        return Err(Error::InvalidArgument(
            "label volume voxel-to-world matrix has a NaN or infinite entry".into(),
        ));
    }
    let row3 = m.row(3);
    if (row3 - DVec4::new(0.0, 0.0, 0.0, 1.0)).abs().max_element() > 1e-9 {
        return Err(Error::InvalidArgument(format!(
            "label volume voxel-to-world matrix is not affine: last row {row3:?}, expected (0, 0, 0, 1)"
        )));
    }
    let r = DMat3::from_mat4(*m);
    for (axis, c) in ["i", "j", "k"].iter().zip([r.x_axis, r.y_axis, r.z_axis]) {
        let s = c.length();
        if !(1e-3..=10.0).contains(&s) {
            return Err(Error::UnitMismatch(format!(
                "label volume voxel size along {axis} is {s} mm (expected 0.001-10 mm: is the \
                 spacing in millimetres?)"
            )));
        }
    }
    let sx = r.x_axis.length() * r.y_axis.length() * r.z_axis.length();
    if r.determinant().abs() < 1e-6 * sx {
        return Err(Error::InvalidArgument(
            "label volume voxel axes are degenerate (the voxel-to-world matrix is singular)".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vol(dims: [usize; 3]) -> LabelVolume {
        let n = dims[0] * dims[1] * dims[2];
        LabelVolume::with_spacing(
            dims,
            [0.5, -0.25, 1.0],
            [1.0, 2.0, 3.0],
            Frame::Lps,
            vec![0; n],
        )
        .unwrap()
    }

    #[test]
    fn crop_keeps_world_positions() {
        let mut v = vol([5, 6, 7]);
        let id = v.idx(3, 4, 5);
        v.labels[id] = 7;
        let c = v.cropped_to_labels();
        assert_eq!(c.dims, [1, 1, 1]);
        assert_eq!(c.labels, vec![7]);
        let w0 = v.world(DVec3::new(3.0, 4.0, 5.0));
        let w1 = c.world(DVec3::ZERO);
        assert!((w0 - w1).length() < 1e-12);
    }

    #[test]
    fn frames_and_axis_codes() {
        let v = vol([2, 2, 2]);
        assert_eq!(v.axis_codes(), "LAS");
        let r = v.to_frame(Frame::Ras);
        assert_eq!(r.axis_codes(), "LAS");
        let p = DVec3::new(1.0, 1.0, 1.0);
        let (a, b) = (v.world(p), r.world(p));
        assert_eq!(b, DVec3::new(-a.x, -a.y, a.z));
        assert_eq!(r.to_frame(Frame::Lps), v);
        assert_eq!(v.spacing(), [0.5, 0.25, 1.0]);
        assert!(!v.is_oblique());
    }

    #[test]
    fn bad_volumes_are_refused() {
        let e = LabelVolume::with_spacing([2, 2, 0], [1.0; 3], [0.0; 3], Frame::Lps, vec![]);
        assert!(e.unwrap_err().to_string().contains("at least 1"));
        let e = LabelVolume::with_spacing([2, 2, 2], [1.0; 3], [0.0; 3], Frame::Lps, vec![0; 7]);
        assert!(e.unwrap_err().to_string().contains("needs 8 labels"));
        let e = LabelVolume::with_spacing(
            [2, 2, 2],
            [1000.0, 1.0, 1.0],
            [0.0; 3],
            Frame::Lps,
            vec![0; 8],
        );
        assert!(e.unwrap_err().to_string().contains("millimetres"));
        let mut m = DMat4::IDENTITY;
        m.y_axis = m.x_axis;
        let e = LabelVolume::new([2, 2, 2], m, Frame::Lps, vec![0; 8]);
        assert!(e.unwrap_err().to_string().contains("singular"));
        m = DMat4::IDENTITY;
        m.w_axis.x = f64::NAN;
        let e = LabelVolume::new([2, 2, 2], m, Frame::Lps, vec![0; 8]);
        assert!(e.unwrap_err().to_string().contains("NaN"));
    }
}
