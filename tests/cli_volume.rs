//! The `toothfuse` binary with CBCT label volumes: `info` on a NIfTI built here (and its error on
//! a volume without orientation), and `fuse --cbct mask.nii.gz` on a real-anatomy phantom made from
//! the STS 2024 mask (../shared/data/real; skipped with a message when absent), checked against
//! the truth through report.json; and `demo --cbct-volume` whose label volumes fuse as well as
//! its CBCT meshes.

mod cli_common;
mod real_data;

use cli_common::{tf, tmp};
use toothfuse::Rigid;
use toothfuse::arch::Jaw;
use toothfuse::phantom::Phantom;
use toothfuse::volume::Frame;

/// A 4×3×2 uint16 NIfTI-1: voxel (2, 1, 1) = 36, sform diag(-0.25, -0.25, 0.5) (or no
/// orientation at all).
fn tiny_nifti(oriented: bool) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (d, v) in [3i16, 4, 3, 2, 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * d..42 + 2 * d].copy_from_slice(&v.to_le_bytes());
    }
    h[70..72].copy_from_slice(&512i16.to_le_bytes());
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[123] = 2;
    if oriented {
        h[254..256].copy_from_slice(&1i16.to_le_bytes());
        let rows = [
            [-0.25f32, 0.0, 0.0, 10.0],
            [0.0, -0.25, 0.0, 20.0],
            [0.0, 0.0, 0.5, -5.0],
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                let at = 280 + 16 * r + 4 * c;
                h[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    let mut labels = [0u16; 24];
    labels[2 + 4 * (1 + 3)] = 36;
    h.extend(labels.iter().flat_map(|v| v.to_le_bytes()));
    h
}

#[test]
fn info_lists_grid_orientation_and_labels() {
    let d = tmp("info");
    let p = d.join("tiny.nii");
    std::fs::write(&p, tiny_nifti(true)).unwrap();
    let o = tf(&["info", p.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}");
    assert!(
        out.contains("NIfTI-1 label volume, 4x3x2 uint16, voxel 0.2500 x 0.2500 x 0.5000 mm"),
        "{out}"
    );
    assert!(
        out.contains("voxel axes LPS (from the sform), axis-aligned; world frame LPS"),
        "{out}"
    );
    assert!(out.contains("label 36: 1 voxels"), "{out}");
    // In RAS the first row of the matrix is (-0.25, 0, 0, 10); in LPS (0.25, 0, 0, -10).
    let ras = String::from_utf8_lossy(&tf(&["info", p.to_str().unwrap(), "--frame", "ras"]).stdout)
        .to_string();
    assert!(
        ras.contains("[   -0.2500     0.0000     0.0000    10.0000]"),
        "{ras}"
    );
    assert!(
        out.contains("[    0.2500     0.0000     0.0000   -10.0000]"),
        "{out}"
    );
    let q = d.join("noorient.nii");
    std::fs::write(&q, tiny_nifti(false)).unwrap();
    let o = tf(&["info", q.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("noorient.nii") && err.contains("no orientation"),
        "{err}"
    );
}

#[test]
fn fuse_from_the_sts_mask_file() {
    let Some(mask) = real_data::real(real_data::STS_MASK) else {
        return;
    };
    // Truth: the mask's lower teeth in its LPS world, which is also the CBCT frame of the file.
    let vol = toothfuse::io::read_label_volume(&mask, Frame::Lps)
        .unwrap()
        .volume;
    let p = real_data::phantom_on(&real_data::lower_teeth(&vol), Jaw::Lower, 3);
    let d = tmp("fuse");
    let ios = d.join("ios.ply");
    let labels = p.ios.vertex_labels.clone().unwrap();
    toothfuse::io::write_mesh(&ios, &p.ios.mesh, &[("label", &labels)]).unwrap();
    let out = d.join("out");
    let o = tf(&[
        "fuse",
        "--ios",
        ios.to_str().unwrap(),
        "--cbct",
        mask.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    // The fragments are named on stderr.
    assert!(
        err.contains("label 11 skipped") && err.contains("label 14 skipped"),
        "{err}"
    );
    let (mean, n) = fused_mean_tre(&out, &p);
    eprintln!("CLI fuse from the STS mask file: mean TRE {mean:.3} mm over {n} teeth");
}

/// Checks `out/report.json` of a fuse of the STS lower-teeth phantom: the ten expected teeth,
/// each watertight; returns the mean TRE (asserted under 0.1 mm) and the number of teeth. The
/// CBCT frame of the file is the phantom's world and the truth's CBCT -> IOS mapping is from the
/// phantom's own CBCT frame, so each estimate is expressed from there.
fn fused_mean_tre(out: &std::path::Path, p: &Phantom) -> (f64, usize) {
    let w2c = p.truth.world_to_cbct;
    let fused = fused_teeth(out);
    let fdis: Vec<u8> = fused.keys().copied().collect();
    assert_eq!(fdis, vec![31, 32, 33, 35, 36, 37, 41, 42, 43, 44]);
    let tre: Vec<f64> = fused
        .iter()
        .map(|(fdi, ios_to_cbct)| {
            let est = ios_to_cbct.inverse().compose(&w2c.inverse());
            p.truth.teeth[fdi].tre(&w2c, &est)
        })
        .collect();
    let mean = tre.iter().sum::<f64>() / tre.len() as f64;
    assert!(mean < 0.1, "mean TRE {mean} ({tre:?})");
    (mean, tre.len())
}

/// The teeth of `out/report.json`, each asserted watertight, with its IOS -> output transform.
fn fused_teeth(out: &std::path::Path) -> std::collections::BTreeMap<u8, Rigid> {
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    rep["teeth"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            assert!(t["watertight"].as_bool().unwrap(), "{t}");
            let m: Vec<f64> = t["ios_to_output"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let fdi = t["fdi"].as_u64().unwrap() as u8;
            (fdi, Rigid::from_row_major(&m.try_into().unwrap()))
        })
        .collect()
}

fn write_nrrd(path: &std::path::Path, v: &toothfuse::volume::LabelVolume) {
    toothfuse::io::write_nrrd(path, v).unwrap();
}

#[test]
fn fuse_from_a_per_jaw_mask_split_by_the_ios() {
    // The mask's lower teeth as the phantom's anatomy; the file holds them merged into
    // DentalSegmentator's lower teeth class (4) in the same LPS world.
    let Some(vol) = real_data::sts_lower_teeth() else {
        return;
    };
    let p = real_data::phantom_on(&vol, Jaw::Lower, 3);
    let d = tmp("split");
    let nrrd = d.join("dentalsegmentator.nrrd");
    write_nrrd(&nrrd, &vol.relabeled(|l| if l != 0 { 4 } else { 0 }));
    let labels = p.ios.vertex_labels.clone().unwrap();
    let ios = d.join("ios.ply");
    toothfuse::io::write_mesh(&ios, &p.ios.mesh, &[("label", &labels)]).unwrap();
    let out = d.join("out");
    let args = |ios: &std::path::Path| {
        let v: Vec<String> = [
            "fuse",
            "--ios",
            ios.to_str().unwrap(),
            "--cbct",
            nrrd.to_str().unwrap(),
            "--cbct-classes",
            "dentalsegmentator",
            "--out",
            out.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v
    };
    let a = args(&ios);
    let o = tf(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("split: tooth 36: split from the per-jaw mask"),
        "{err}"
    );
    let split: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("split.json")).unwrap()).unwrap();
    let teeth = split["jaws"][0]["teeth"].as_array().unwrap();
    assert_eq!(teeth.len(), 10);
    for t in teeth {
        assert!(t["refused"].is_null(), "{t}");
        assert!(t["contested_share"].as_f64().unwrap() < 0.05, "{t}");
    }
    let (mean, _) = fused_mean_tre(&out, &p);
    eprintln!("CLI fuse from a per-jaw mask split by the IOS: mean TRE {mean:.3} mm");
    // Without --cbct-classes the classes are detected and split the same way (register only).
    let o = tf(&[
        "register",
        "--ios",
        ios.to_str().unwrap(),
        "--cbct",
        nrrd.to_str().unwrap(),
        "--out",
        d.join("register.json").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("look like DentalSegmentator classes"), "{err}");
    assert!(err.contains("split: tooth 44: split"), "{err}");
    // The same IOS numbered as upper teeth: refused, naming the cause.
    let upper: Vec<i32> = labels
        .iter()
        .map(|&l| if l > 0 { l - 20 } else { 0 })
        .collect();
    let ios_up = d.join("ios_upper.ply");
    toothfuse::io::write_mesh(&ios_up, &p.ios.mesh, &[("label", &upper)]).unwrap();
    let a = args(&ios_up);
    let o = tf(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("other jaw"), "{err}");
}

/// Per fused tooth of `out/report.json` (output frame: the phantom's CBCT frame, where the demo
/// writes its CBCT), the TRE of its registration against the phantom's truth.
fn tre_by_tooth(out: &std::path::Path, p: &Phantom) -> std::collections::BTreeMap<u8, f64> {
    fused_teeth(out)
        .into_iter()
        .map(|(fdi, ios_to_cbct)| {
            let tre = p.truth.teeth[&fdi].tre(&p.truth.world_to_cbct, &ios_to_cbct.inverse());
            (fdi, tre)
        })
        .collect()
}

/// `toothfuse demo --cbct-volume 0.3` writes the CBCT teeth as a per-tooth FDI label volume and
/// as DentalSegmentator's one upper-teeth class; fusing the IOS with either (the second split by
/// the IOS crowns) gives every tooth of the mesh path, watertight, with its TRE.
#[test]
fn demo_label_volumes_fuse_like_the_meshes() {
    let d = tmp("demo");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let o = tf(&[
        "demo",
        "--seed",
        "3",
        "--jaw",
        "upper",
        "--variant",
        "partial",
        "--cbct-volume",
        "0.3",
        "--out",
        &s(&d),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info = tf(&["info", &s(&d.join("cbct_teeth_class.nrrd"))]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success() && text.contains("LPS"), "{text}");
    let fuse = |cbct: &str, extra: &[&str], name: &str| {
        let out = d.join(name);
        let mut a: Vec<String> = ["fuse", "--ios"].map(String::from).to_vec();
        a.extend([s(&d.join("ios.ply")), "--cbct".into(), s(&d.join(cbct))]);
        a.extend(["--out".into(), s(&out)]);
        a.extend(extra.iter().map(|x| x.to_string()));
        let o = tf(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        out
    };
    let p = Phantom::generate(&toothfuse::phantom::PhantomOptions {
        seed: 3,
        jaw: Jaw::Upper,
        variant: toothfuse::phantom::Variant::PartialArch,
        ..Default::default()
    })
    .unwrap();
    let meshes = tre_by_tooth(&fuse("cbct.ply", &[], "meshes"), &p);
    let labels = tre_by_tooth(&fuse("cbct_labels.nrrd", &[], "labels"), &p);
    let split = tre_by_tooth(
        &fuse(
            "cbct_teeth_class.nrrd",
            &["--cbct-classes", "dentalsegmentator"],
            "split",
        ),
        &p,
    );
    let mean = |m: &std::collections::BTreeMap<u8, f64>| m.values().sum::<f64>() / m.len() as f64;
    eprintln!(
        "demo jaw: mean TRE meshes {:.3} mm, per-tooth volume {:.3} mm, per-jaw class split {:.3} mm",
        mean(&meshes),
        mean(&labels),
        mean(&split)
    );
    assert_eq!(meshes.len(), 5, "{meshes:?}");
    assert_eq!(
        labels.keys().collect::<Vec<_>>(),
        meshes.keys().collect::<Vec<_>>()
    );
    assert_eq!(
        split.keys().collect::<Vec<_>>(),
        meshes.keys().collect::<Vec<_>>()
    );
    assert!(
        mean(&labels) <= 1.1 * mean(&meshes) + 0.02,
        "{labels:?} vs {meshes:?}"
    );
    assert!(
        mean(&split) <= 1.5 * mean(&labels),
        "{split:?} vs {labels:?}"
    );
}
