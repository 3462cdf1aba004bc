//! Writing a label volume as NRRD (`.nrrd`, read by 3D Slicer, ITK and this crate): the text
//! header with the voxel-to-world mapping (`space`, `space directions`, `space origin`), then the
//! labels as little-endian `ushort`, gzip-compressed, in the same file.

use crate::volume::{Frame, LabelVolume};
use crate::{Error, Result};
use flate2::Compression;
use flate2::write::GzEncoder;
use std::io::Write;
use std::path::Path;

/// The NRRD bytes of `v`: its labels (i fastest) and its voxel-to-world mapping in its frame.
pub fn nrrd_bytes(v: &LabelVolume) -> Result<Vec<u8>> {
    let m = v.voxel_to_world;
    let vec3 = |c: glam::DVec3| format!("({:?},{:?},{:?})", c.x, c.y, c.z);
    let space = match v.frame {
        Frame::Lps => "left-posterior-superior",
        Frame::Ras => "right-anterior-superior",
    };
    let header = format!(
        "NRRD0004\n# written by toothfuse\ntype: ushort\ndimension: 3\nspace: {space}\n\
         sizes: {} {} {}\nspace directions: {} {} {}\nkinds: domain domain domain\n\
         endian: little\nencoding: gzip\nspace origin: {}\n\n",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        vec3(m.x_axis.truncate()),
        vec3(m.y_axis.truncate()),
        vec3(m.z_axis.truncate()),
        vec3(m.w_axis.truncate()),
    );
    let mut out = header.into_bytes();
    let mut gz = GzEncoder::new(Vec::new(), Compression::fast());
    let raw: Vec<u8> = v.labels.iter().flat_map(|l| l.to_le_bytes()).collect();
    let io = |e: std::io::Error| Error::Io(format!("compressing the NRRD data: {e}"));
    gz.write_all(&raw).map_err(io)?;
    out.extend(gz.finish().map_err(io)?);
    Ok(out)
}

/// Writes `v` to `path` as NRRD (see [`nrrd_bytes`]).
pub fn write_nrrd(path: impl AsRef<Path>, v: &LabelVolume) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, nrrd_bytes(v)?).map_err(|e| Error::Io(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::volume::read_nrrd_from;
    use glam::{DMat3, DMat4, DVec3};

    /// An oblique, anisotropic volume written and read back: the same labels at the same world
    /// places, in LPS and in RAS.
    #[test]
    fn round_trips_labels_and_placement() {
        let dims = [5, 4, 3];
        let labels: Vec<u16> = (0..60)
            .map(|i| if i % 7 == 0 { 0 } else { 11 + i % 5 })
            .collect();
        let lin = DMat3::from_rotation_z(0.4)
            * DMat3::from_rotation_x(-0.3)
            * DMat3::from_diagonal(DVec3::new(0.25, 0.3, 0.5));
        let affine = DMat4::from_mat3_translation(lin, DVec3::new(-12.5, 40.0, 7.25));
        for frame in [Frame::Lps, Frame::Ras] {
            let v = LabelVolume::new(dims, affine, frame, labels.clone()).unwrap();
            let bytes = nrrd_bytes(&v).unwrap();
            let back = read_nrrd_from("t.nrrd", &bytes[..]).unwrap().volume;
            let want = v.cropped_to_labels();
            assert_eq!(back.dims, want.dims);
            assert_eq!(back.labels, want.labels);
            assert_eq!(back.frame, frame);
            assert!(back.voxel_to_world.abs_diff_eq(want.voxel_to_world, 1e-12));
        }
    }
}
