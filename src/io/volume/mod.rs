//! CBCT label volume files: NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`) and NRRD (`.nrrd`,
//! `.seg.nrrd`, raw or gzip data), read into a [`LabelVolume`] cropped to the bounding box of its
//! labels (a 640×640×400 CBCT mask is read slice by slice and only the slices holding labels are
//! kept).
//!
//! The voxel-to-world matrix comes from the file: NIfTI sform (or qform when sform is absent),
//! in RAS; NRRD `space directions` and `space origin` in the file's `space` (LPS or RAS). A file
//! with no orientation (NIfTI with sform and qform codes 0, NRRD with only `spacings`) is refused,
//! as is data that is not a label map (non-integer values, negative labels, thousands of
//! distinct values as in an intensity image).

mod nifti;
mod nrrd;
mod nrrd_write;

pub use nifti::read_nifti_from;
pub use nrrd::read_nrrd_from;
pub use nrrd_write::{nrrd_bytes, write_nrrd};

use crate::volume::{Frame, LabelVolume};
use crate::{Error, Result};
use glam::{DMat4, DVec3};
use std::io::Read;
use std::path::Path;

/// What a volume file said about itself, beside the labels.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeHeader {
    /// `"NIfTI-1"`, `"NIfTI-2"` or `"NRRD"`.
    pub format: &'static str,
    /// Voxels along i, j, k in the file (before cropping).
    pub full_dims: [usize; 3],
    /// The stored element type (`"uint16"`, ...).
    pub element: &'static str,
    /// Where the orientation came from (`"sform"`, `"qform"`, `"space directions"`).
    pub orientation_source: &'static str,
    /// Voxel-to-world of the whole file volume, in [`LabelVolume::frame`].
    pub full_voxel_to_world: DMat4,
    /// Named segments of a 3D Slicer `.seg.nrrd`: (label value, name).
    pub segments: Vec<(u16, String)>,
}

/// A volume file read: the cropped label volume and the header facts.
#[derive(Clone, Debug)]
pub struct VolumeFile {
    /// Labels cropped to their bounding box (the affine keeps world positions).
    pub volume: LabelVolume,
    /// What the header said.
    pub header: VolumeHeader,
}

/// True for paths a volume reader handles: `.nii`, `.nii.gz`, `.nrrd` and `.seg.nrrd`
/// (case-insensitive). Detached headers (`.nhdr`, `.hdr`/`.img`) are not supported.
pub fn is_volume_path(path: &Path) -> bool {
    let n = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default()
        .to_ascii_lowercase();
    n.ends_with(".nii") || n.ends_with(".nii.gz") || n.ends_with(".nrrd")
}

/// Reads a label volume file (by extension: `.nii`, `.nii.gz`, `.nrrd`, `.seg.nrrd`) and
/// returns it in `frame` (LPS or RAS), cropped to its labels.
pub fn read_label_volume(path: impl AsRef<Path>, frame: Frame) -> Result<VolumeFile> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let file =
        std::fs::File::open(path).map_err(|e| Error::Io(format!("{name}: cannot read: {e}")))?;
    let reader = std::io::BufReader::with_capacity(1 << 20, file);
    let lower = name.to_ascii_lowercase();
    let mut vf = if lower.ends_with(".nii") || lower.ends_with(".nii.gz") {
        read_nifti_from(&name, reader)?
    } else if lower.ends_with(".nrrd") {
        read_nrrd_from(&name, reader)?
    } else {
        return Err(Error::Io(format!(
            "{name}: unknown volume file extension (expected .nii, .nii.gz, .nrrd or .seg.nrrd)"
        )));
    };
    if vf.volume.frame != frame {
        let flip = glam::DMat4::from_diagonal(glam::DVec4::new(-1.0, -1.0, 1.0, 1.0));
        vf.header.full_voxel_to_world = flip * vf.header.full_voxel_to_world;
        vf.volume = vf.volume.to_frame(frame);
    }
    Ok(vf)
}

/// Stored element types of label data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Elem {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl Elem {
    pub(crate) fn size(self) -> usize {
        match self {
            Elem::U8 | Elem::I8 => 1,
            Elem::U16 | Elem::I16 => 2,
            Elem::U32 | Elem::I32 | Elem::F32 => 4,
            Elem::U64 | Elem::I64 | Elem::F64 => 8,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Elem::U8 => "uint8",
            Elem::I8 => "int8",
            Elem::U16 => "uint16",
            Elem::I16 => "int16",
            Elem::U32 => "uint32",
            Elem::I32 => "int32",
            Elem::U64 => "uint64",
            Elem::I64 => "int64",
            Elem::F32 => "float32",
            Elem::F64 => "float64",
        }
    }

    /// Element `n` of `bytes` as f64.
    #[inline]
    fn get(self, b: &[u8], n: usize, big: bool) -> f64 {
        let s = n * self.size();
        macro_rules! rd {
            ($t:ty, $w:expr) => {{
                let a: [u8; $w] = b[s..s + $w].try_into().unwrap_or([0; $w]);
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Elem::U8 => b[s] as f64,
            Elem::I8 => b[s] as i8 as f64,
            Elem::U16 => rd!(u16, 2),
            Elem::I16 => rd!(i16, 2),
            Elem::U32 => rd!(u32, 4),
            Elem::I32 => rd!(i32, 4),
            Elem::U64 => rd!(u64, 8),
            Elem::I64 => rd!(i64, 8),
            Elem::F32 => rd!(f32, 4),
            Elem::F64 => rd!(f64, 8),
        }
    }
}

/// How the stored values become labels: `label = slope * stored + inter`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Decode {
    pub elem: Elem,
    pub big_endian: bool,
    pub slope: f64,
    pub inter: f64,
}

/// Above this many distinct non-zero values the data is an image, not a segmentation.
const MAX_DISTINCT_LABELS: usize = 1000;

/// Reads `dims[2]` slices of `dims[0] * dims[1]` elements from `r`, checks that they are labels
/// and keeps the bounding box of the non-zero ones: the labels and the box's low corner.
pub(crate) fn read_slices(
    name: &str,
    r: &mut impl Read,
    dims: [usize; 3],
    dec: Decode,
) -> Result<(Vec<u16>, [usize; 3], [usize; 3])> {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    let mut buf = vec![0u8; plane * dec.elem.size()];
    let mut slices: Vec<(usize, Vec<u16>)> = Vec::new();
    let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
    let mut seen = vec![false; 65536];
    let mut distinct = 0usize;
    for k in 0..nz {
        r.read_exact(&mut buf).map_err(|e| {
            Error::Io(format!(
                "{name}: voxel data ends early in slice {k} of {nz} ({e}); expected {} bytes per slice",
                buf.len()
            ))
        })?;
        let mut labels = vec![0u16; plane];
        let mut any = false;
        let size = dec.elem.size();
        for (n, out) in labels.iter_mut().enumerate() {
            // Background (all-zero bytes: 0 in every element type) is most of a CBCT mask.
            if dec.inter == 0.0 && buf[n * size..(n + 1) * size].iter().all(|&b| b == 0) {
                continue;
            }
            let raw = dec.elem.get(&buf, n, dec.big_endian);
            let v = dec.slope * raw + dec.inter;
            let l = check_label(name, v, [n % nx, n / nx, k])?;
            if l == 0 {
                continue;
            }
            if !seen[l as usize] {
                seen[l as usize] = true;
                distinct += 1;
                if distinct > MAX_DISTINCT_LABELS {
                    return Err(Error::InvalidArgument(format!(
                        "{name}: more than {MAX_DISTINCT_LABELS} distinct values: this looks like \
                         an intensity image, not a label map (a segmentation is needed)"
                    )));
                }
            }
            *out = l;
            any = true;
            let (i, j) = (n % nx, n / nx);
            lo = [lo[0].min(i), lo[1].min(j)];
            hi = [hi[0].max(i), hi[1].max(j)];
        }
        if any {
            slices.push((k, labels));
        }
    }
    let (Some(first), Some(last)) = (slices.first(), slices.last()) else {
        return Err(Error::MissingData(format!(
            "{name}: the volume holds no label (every voxel is 0)"
        )));
    };
    let (k0, k1) = (first.0, last.0);
    let cd = [hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, k1 - k0 + 1];
    let mut out = vec![0u16; cd[0] * cd[1] * cd[2]];
    for (k, labels) in &slices {
        for j in lo[1]..=hi[1] {
            let src = &labels[j * nx + lo[0]..=j * nx + hi[0]];
            let dst = cd[0] * ((j - lo[1]) + cd[1] * (k - k0));
            out[dst..dst + cd[0]].copy_from_slice(src);
        }
    }
    Ok((out, [lo[0], lo[1], k0], cd))
}

fn check_label(name: &str, v: f64, at: [usize; 3]) -> Result<u16> {
    let r = v.round();
    if !v.is_finite() || (v - r).abs() > 1e-3 {
        return Err(Error::InvalidArgument(format!(
            "{name}: voxel {at:?} holds {v}, not an integer label: this looks like an image, not a \
             label map (a segmentation is needed)"
        )));
    }
    if !(0.0..=65535.0).contains(&r) {
        return Err(Error::InvalidArgument(format!(
            "{name}: voxel {at:?} holds label {r}: labels must be 0-65535 (a negative or huge value \
             suggests an intensity image, not a label map)"
        )));
    }
    Ok(r as u16)
}

/// Builds the cropped volume from [`read_slices`]'s output and the full affine.
pub(crate) fn cropped(
    full: DMat4,
    frame: Frame,
    labels: Vec<u16>,
    lo: [usize; 3],
    dims: [usize; 3],
) -> Result<LabelVolume> {
    let shift = DMat4::from_translation(DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64));
    LabelVolume::new(dims, full * shift, frame, labels)
}
