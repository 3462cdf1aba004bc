//! Label volume readers on tiny files built here (NIfTI-1/2 with sform or qform, either byte
//! order, gzip; NRRD raw/gzip in LPS, RAS and LAS; a one-layer .seg.nrrd), the orientation
//! conventions, and the errors on volumes that are not usable label maps.

use glam::{DMat4, DVec3};
use std::io::Write;
use std::path::PathBuf;
use toothfuse::io::read_label_volume;
use toothfuse::volume::Frame;

const DIMS: [usize; 3] = [4, 3, 2];

/// Labels: 0 except voxel (2, 1, 1) = 36 and voxel (1, 0, 0) = 11.
fn labels() -> Vec<u16> {
    let mut l = vec![0u16; 24];
    l[2 + 4 * (1 + 3)] = 36;
    l[1] = 11;
    l
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("toothfuse_io_volume_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn gz(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// How a test NIfTI places its voxels.
enum Orient {
    Sform([[f32; 4]; 3]),
    /// quaternion b, c, d; qfac; pixdim; offset.
    Qform([f32; 3], f32, [f32; 3], [f32; 3]),
    None,
}

fn nifti1(orient: &Orient, datatype: i16, data: &[u8], big: bool) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let put = |h: &mut Vec<u8>, at: usize, b: &[u8]| {
        let mut b = b.to_vec();
        if big {
            b.reverse();
        }
        h[at..at + b.len()].copy_from_slice(&b);
    };
    put(&mut h, 0, &348i32.to_le_bytes());
    for (d, v) in [
        3i16,
        DIMS[0] as i16,
        DIMS[1] as i16,
        DIMS[2] as i16,
        1,
        1,
        1,
        1,
    ]
    .iter()
    .enumerate()
    {
        put(&mut h, 40 + 2 * d, &v.to_le_bytes());
    }
    put(&mut h, 70, &datatype.to_le_bytes());
    put(&mut h, 108, &352f32.to_le_bytes());
    h[123] = 2; // mm
    match orient {
        Orient::Sform(rows) => {
            put(&mut h, 254, &1i16.to_le_bytes());
            for (r, row) in rows.iter().enumerate() {
                for (c, v) in row.iter().enumerate() {
                    put(&mut h, 280 + 16 * r + 4 * c, &v.to_le_bytes());
                }
            }
        }
        Orient::Qform(q, qfac, pix, off) => {
            put(&mut h, 252, &1i16.to_le_bytes());
            put(&mut h, 76, &qfac.to_le_bytes());
            for d in 0..3 {
                put(&mut h, 80 + 4 * d, &pix[d].to_le_bytes());
                put(&mut h, 256 + 4 * d, &q[d].to_le_bytes());
                put(&mut h, 268 + 4 * d, &off[d].to_le_bytes());
            }
        }
        Orient::None => {}
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    h
}

fn nifti2_sform(rows: [[f64; 4]; 3], data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 544];
    h[0..4].copy_from_slice(&540i32.to_le_bytes());
    h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
    h[12..14].copy_from_slice(&512i16.to_le_bytes());
    for (d, v) in [
        3i64,
        DIMS[0] as i64,
        DIMS[1] as i64,
        DIMS[2] as i64,
        1,
        1,
        1,
        1,
    ]
    .iter()
    .enumerate()
    {
        h[16 + 8 * d..24 + 8 * d].copy_from_slice(&v.to_le_bytes());
    }
    h[168..176].copy_from_slice(&544i64.to_le_bytes());
    h[348..352].copy_from_slice(&1i32.to_le_bytes());
    for (r, row) in rows.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            let at = 400 + 32 * r + 8 * c;
            h[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
    }
    h[500..504].copy_from_slice(&2i32.to_le_bytes());
    h.extend_from_slice(data);
    h
}

fn u16_bytes(big: bool) -> Vec<u8> {
    labels()
        .iter()
        .flat_map(|v| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        })
        .collect()
}

/// World position (in the volume's frame) of the centre of the voxel labelled 36.
fn centre_of_36(path: &PathBuf, frame: Frame) -> DVec3 {
    let vf = read_label_volume(path, frame).unwrap();
    let v = &vf.volume;
    assert_eq!(vf.header.full_dims, DIMS);
    assert_eq!(v.frame, frame);
    let counts = v.label_counts();
    assert_eq!(counts.keys().copied().collect::<Vec<_>>(), vec![11, 36]);
    let id = v.labels.iter().position(|&l| l == 36).unwrap();
    let ijk = DVec3::new(
        (id % v.dims[0]) as f64,
        ((id / v.dims[0]) % v.dims[1]) as f64,
        (id / (v.dims[0] * v.dims[1])) as f64,
    );
    v.world(ijk)
}

const SROW_LPS_STYLE: [[f32; 4]; 3] = [
    [-0.25, 0.0, 0.0, 10.0],
    [0.0, -0.25, 0.0, 20.0],
    [0.0, 0.0, 0.5, -5.0],
];

#[test]
fn nifti_sform_negative_spacing_lps_and_ras() {
    let p = tmp("a.nii");
    std::fs::write(
        &p,
        nifti1(
            &Orient::Sform(SROW_LPS_STYLE),
            512,
            &u16_bytes(false),
            false,
        ),
    )
    .unwrap();
    // RAS (NIfTI's own world): voxel (2, 1, 1) at (10 - 0.5, 20 - 0.25, -5 + 0.5).
    let ras = centre_of_36(&p, Frame::Ras);
    assert!(
        (ras - DVec3::new(9.5, 19.75, -4.5)).length() < 1e-9,
        "{ras}"
    );
    // LPS: x and y negated.
    let lps = centre_of_36(&p, Frame::Lps);
    assert!(
        (lps - DVec3::new(-9.5, -19.75, -4.5)).length() < 1e-9,
        "{lps}"
    );
    let vf = read_label_volume(&p, Frame::Lps).unwrap();
    assert_eq!(vf.header.orientation_source, "sform");
    assert_eq!(vf.header.format, "NIfTI-1");
    assert_eq!(vf.volume.spacing(), [0.25, 0.25, 0.5]);
    // Negative x/y steps in RAS point Left and Posterior: the voxel axes are L, P, S.
    assert_eq!(vf.volume.axis_codes(), "LPS");
    // The same file gzip-compressed, and big-endian, read the same.
    let pg = tmp("a.nii.gz");
    std::fs::write(
        &pg,
        gz(&nifti1(
            &Orient::Sform(SROW_LPS_STYLE),
            512,
            &u16_bytes(false),
            false,
        )),
    )
    .unwrap();
    assert_eq!(centre_of_36(&pg, Frame::Ras), ras);
    let pb = tmp("b.nii");
    std::fs::write(
        &pb,
        nifti1(&Orient::Sform(SROW_LPS_STYLE), 512, &u16_bytes(true), true),
    )
    .unwrap();
    assert_eq!(centre_of_36(&pb, Frame::Ras), ras);
}

#[test]
fn nifti_qform_oblique_with_qfac() {
    // 90° about z: quaternion (a, b, c, d) = (cos 45°, 0, 0, sin 45°); qfac -1 flips k.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let o = Orient::Qform([0.0, 0.0, s], -1.0, [0.3, 0.4, 0.5], [1.0, 2.0, 3.0]);
    let p = tmp("q.nii");
    std::fs::write(&p, nifti1(&o, 512, &u16_bytes(false), false)).unwrap();
    let ras = centre_of_36(&p, Frame::Ras);
    // i → +y·0.3, j → −x·0.4, k → −z·0.5: (2, 1, 1) ↦ (1 − 0.4, 2 + 0.6, 3 − 0.5).
    assert!((ras - DVec3::new(0.6, 2.6, 2.5)).length() < 1e-6, "{ras}");
    let vf = read_label_volume(&p, Frame::Ras).unwrap();
    assert_eq!(vf.header.orientation_source, "qform");
    assert_eq!(vf.volume.axis_codes(), "ALI");
    // An oblique sform (30° about x) in NIfTI-2.
    let a = 30f64.to_radians();
    let rows = [
        [0.25, 0.0, 0.0, 0.0],
        [0.0, 0.25 * a.cos(), -0.25 * a.sin(), 0.0],
        [0.0, 0.25 * a.sin(), 0.25 * a.cos(), 0.0],
    ];
    let p2 = tmp("o.nii");
    std::fs::write(&p2, nifti2_sform(rows, &u16_bytes(false))).unwrap();
    let vf = read_label_volume(&p2, Frame::Ras).unwrap();
    assert_eq!(vf.header.format, "NIfTI-2");
    assert!(vf.volume.is_oblique());
    let w = centre_of_36(&p2, Frame::Ras);
    let want = DVec3::new(
        0.5,
        0.25 * a.cos() - 0.25 * a.sin(),
        0.25 * a.sin() + 0.25 * a.cos(),
    );
    assert!((w - want).length() < 1e-12, "{w} vs {want}");
}

fn nrrd(
    space: &str,
    dirs: &str,
    origin: &str,
    encoding: &str,
    data: &[u8],
    extra: &str,
) -> Vec<u8> {
    let mut t = format!(
        "NRRD0004\n# Complete NRRD file format specification at:\ntype: unsigned short\n\
         dimension: 3\nspace: {space}\nsizes: 4 3 2\nspace directions: {dirs}\n\
         kinds: domain domain domain\nendian: little\nencoding: {encoding}\n\
         space origin: {origin}\n{extra}\n"
    )
    .into_bytes();
    if !extra.is_empty() {
        t.push(b'\n');
    }
    t.extend_from_slice(data);
    t
}

#[test]
fn nrrd_lps_ras_las_agree_in_world() {
    let dirs = "(0.5,0,0) (0,0.5,0) (0,0,1)";
    let p = tmp("lps.nrrd");
    std::fs::write(
        &p,
        nrrd(
            "left-posterior-superior",
            dirs,
            "(-10,-20,5)",
            "raw",
            &u16_bytes(false),
            "",
        ),
    )
    .unwrap();
    let lps = centre_of_36(&p, Frame::Lps);
    assert!(
        (lps - DVec3::new(-9.0, -19.5, 6.0)).length() < 1e-12,
        "{lps}"
    );
    assert_eq!(centre_of_36(&p, Frame::Ras), DVec3::new(9.0, 19.5, 6.0));
    // The same voxels described in RAS (directions and origin negated in x, y), gzip.
    let p2 = tmp("ras.seg.nrrd");
    std::fs::write(
        &p2,
        nrrd(
            "right-anterior-superior",
            "(-0.5,0,0) (0,-0.5,0) (0,0,1)",
            "(10,20,5)",
            "gzip",
            &gz(&u16_bytes(false)),
            "Segment0_Name:=tooth 11\nSegment0_LabelValue:=11\nSegment1_Name:=tooth 36\nSegment1_LabelValue:=36",
        ),
    )
    .unwrap();
    assert!((centre_of_36(&p2, Frame::Lps) - lps).length() < 1e-12);
    let vf = read_label_volume(&p2, Frame::Lps).unwrap();
    assert_eq!(
        vf.header.segments,
        vec![(11, "tooth 11".to_string()), (36, "tooth 36".to_string())]
    );
    // Left-anterior-superior: y negated relative to LPS.
    let p3 = tmp("las.nrrd");
    std::fs::write(
        &p3,
        nrrd(
            "left-anterior-superior",
            "(0.5,0,0) (0,-0.5,0) (0,0,1)",
            "(-10,20,5)",
            "raw",
            &u16_bytes(false),
            "",
        ),
    )
    .unwrap();
    assert!((centre_of_36(&p3, Frame::Lps) - lps).length() < 1e-12);
}

#[test]
fn seg_nrrd_one_layer_4d() {
    let mut t = b"NRRD0005\ntype: uint8\ndimension: 4\nspace: left-posterior-superior\n\
        sizes: 1 4 3 2\nspace directions: none (0.25,0,0) (0,0.25,0) (0,0,0.25)\n\
        kinds: list domain domain domain\nencoding: raw\nspace origin: (0,0,0)\n\n"
        .to_vec();
    t.extend(labels().iter().map(|&l| l as u8));
    let p = tmp("layer.seg.nrrd");
    std::fs::write(&p, &t).unwrap();
    let w = centre_of_36(&p, Frame::Lps);
    assert_eq!(w, DVec3::new(0.5, 0.25, 0.25));
    // Two layers: refused with the reason.
    let t2 = String::from_utf8_lossy(&t).replace("sizes: 1 4 3 2", "sizes: 2 4 3 2");
    let p2 = tmp("layers.seg.nrrd");
    std::fs::write(&p2, t2.as_bytes()).unwrap();
    let e = read_label_volume(&p2, Frame::Lps).unwrap_err().to_string();
    assert!(e.contains("2 layers"), "{e}");
}

fn expect_err(name: &str, bytes: &[u8], want: &str) {
    let p = tmp(name);
    std::fs::write(&p, bytes).unwrap();
    let e = read_label_volume(&p, Frame::Lps).unwrap_err().to_string();
    assert!(e.contains(want), "{name}: {e:?} should say {want:?}");
    assert!(e.contains(name), "{name}: {e:?} should name the file");
}

#[test]
fn bad_volumes_are_refused_with_reasons() {
    let sf = Orient::Sform(SROW_LPS_STYLE);
    expect_err(
        "noorient.nii",
        &nifti1(&Orient::None, 512, &u16_bytes(false), false),
        "no orientation",
    );
    // float data that is not integral: an image.
    let f: Vec<u8> = (0..24)
        .flat_map(|i| (i as f32 * 0.37).to_le_bytes())
        .collect();
    expect_err(
        "float.nii",
        &nifti1(&sf, 16, &f, false),
        "not an integer label",
    );
    // float data holding integers is a label map.
    let fi: Vec<u8> = labels()
        .iter()
        .flat_map(|&l| (l as f32).to_le_bytes())
        .collect();
    let p = tmp("floatlabels.nii");
    std::fs::write(&p, nifti1(&sf, 16, &fi, false)).unwrap();
    assert_eq!(
        read_label_volume(&p, Frame::Lps)
            .unwrap()
            .volume
            .label_counts()
            .len(),
        2
    );
    // negative int16 values (CT intensities).
    let neg: Vec<u8> = (0..24)
        .flat_map(|i| (-1000i16 + i as i16).to_le_bytes())
        .collect();
    expect_err(
        "ct.nii",
        &nifti1(&sf, 4, &neg, false),
        "labels must be 0-65535",
    );
    // truncated data.
    let full = nifti1(&sf, 512, &u16_bytes(false), false);
    expect_err("short.nii", &full[..full.len() - 5], "ends early");
    // all background.
    expect_err(
        "empty.nii",
        &nifti1(&sf, 512, &[0u8; 48], false),
        "holds no label",
    );
    // not NIfTI at all.
    expect_err("junk.nii", &[7u8; 400], "not a NIfTI file");
    // complex datatype.
    expect_err(
        "complex.nii",
        &nifti1(&sf, 32, &[0u8; 192], false),
        "datatype 32",
    );
    // a 4-D series.
    let mut four = nifti1(&sf, 512, &u16_bytes(false), false);
    four[40..42].copy_from_slice(&4i16.to_le_bytes());
    four[48..50].copy_from_slice(&2i16.to_le_bytes());
    expect_err("series.nii", &four, "label volume is 3-D");
    // NRRD without orientation, without space, detached, bad encoding.
    let no_dirs = String::from_utf8_lossy(&nrrd("lps", "X", "(0,0,0)", "raw", &[], ""))
        .replace("space directions: X\n", "spacings: 1 1 1\n");
    let mut b = no_dirs.into_bytes();
    b.extend(u16_bytes(false));
    expect_err("nodirs.nrrd", &b, "no `space directions`");
    let dirs = "(1,0,0) (0,1,0) (0,0,1)";
    let no_space =
        String::from_utf8_lossy(&nrrd("lps", dirs, "(0,0,0)", "raw", &u16_bytes(false), ""))
            .replace("space: lps\n", "");
    expect_err("nospace.nrrd", no_space.as_bytes(), "no `space` field");
    expect_err(
        "detached.nrrd",
        &nrrd("lps", dirs, "(0,0,0)", "raw", &[], "data file: x.raw"),
        "detached data",
    );
    expect_err(
        "bz.nrrd",
        &nrrd("lps", dirs, "(0,0,0)", "bzip2", &u16_bytes(false), ""),
        "encoding `bzip2`",
    );
    expect_err(
        "metres.nrrd",
        &nrrd(
            "lps",
            "(0.0002,0,0) (0,1,0) (0,0,1)",
            "(0,0,0)",
            "raw",
            &u16_bytes(false),
            "",
        ),
        "millimetres",
    );
}

#[test]
fn full_affine_is_reported_uncropped() {
    let p = tmp("full.nii");
    std::fs::write(
        &p,
        nifti1(
            &Orient::Sform(SROW_LPS_STYLE),
            512,
            &u16_bytes(false),
            false,
        ),
    )
    .unwrap();
    let vf = read_label_volume(&p, Frame::Ras).unwrap();
    let want = DMat4::from_cols_array_2d(&[
        [-0.25, 0.0, 0.0, 0.0],
        [0.0, -0.25, 0.0, 0.0],
        [0.0, 0.0, 0.5, 0.0],
        [10.0, 20.0, -5.0, 1.0],
    ]);
    assert_eq!(vf.header.full_voxel_to_world, want);
    // Cropped to labels 11 at (1,0,0) and 36 at (2,1,1): 2 × 2 × 2 voxels.
    assert_eq!(vf.volume.dims, [2, 2, 2]);
}
