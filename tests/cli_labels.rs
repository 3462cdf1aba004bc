//! Label arrays as dental tools write them, through the `toothfuse` binary: a teeth-only IOS (no
//! gingiva, as the DCBIA tools export per tooth) with Universal numbers in a `UniversalID` point
//! array, as `.vtp` and legacy `.vtk`, read by `info` and `fuse` (automatically and by name) and
//! mapped to FDI; ambiguous numbers refused unless `--labels` says; a file without a label array
//! refused with the list of its arrays.

mod cli_common;

use cli_common::{tf, tmp};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use toothfuse::io::{VtpEncoding, fdi_to_universal, write_teeth_dir, write_vtp};
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::{Rigid, TriMesh};

/// The binary run with `args`, asserted to succeed: its standard output and error together.
fn ok(args: &[&str]) -> String {
    let o = tf(args);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    );
    assert!(o.status.success(), "{args:?} failed:\n{out}\n{err}");
    out + &err
}

fn fails(args: &[&str]) -> String {
    let o = tf(args);
    assert!(!o.status.success(), "{args:?} should fail");
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(err.starts_with("toothfuse: error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The crowns `fdis` side by side in one mesh (no gingiva), with per-vertex labels `label(fdi)`.
fn teeth_only(crowns: &BTreeMap<u8, TriMesh>, label: impl Fn(u8) -> i32) -> (TriMesh, Vec<i32>) {
    let (mut pos, mut tris, mut labels) = (Vec::new(), Vec::new(), Vec::new());
    for (&fdi, c) in crowns {
        let base = pos.len() as u32;
        pos.extend_from_slice(&c.positions);
        tris.extend(c.triangles.iter().map(|t| t.map(|v| v + base)));
        labels.extend(std::iter::repeat_n(label(fdi), c.positions.len()));
    }
    (TriMesh::new(pos, tris), labels)
}

fn write_vtp_file(path: &Path, mesh: &TriMesh, point_props: &[(&str, &[i32])]) {
    let mut bytes = Vec::new();
    let enc = VtpEncoding::AppendedRaw {
        compressed: true,
        header64: false,
    };
    write_vtp(&mut bytes, mesh, point_props, &[], enc).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// A legacy ASCII `.vtk` as VTK writes it: the label as `SCALARS … int` with a lookup table and
/// a decoy `RegionId` in a `FIELD` block.
fn write_legacy_vtk(path: &Path, mesh: &TriMesh, name: &str, labels: &[i32]) {
    let mut t = String::from("# vtk DataFile Version 4.2\nteeth\nASCII\nDATASET POLYDATA\n");
    let _ = writeln!(t, "POINTS {} double", mesh.positions.len());
    for p in &mesh.positions {
        let _ = writeln!(t, "{} {} {}", p.x, p.y, p.z);
    }
    let n = mesh.triangles.len();
    let _ = writeln!(t, "POLYGONS {n} {}", 4 * n);
    for f in &mesh.triangles {
        let _ = writeln!(t, "3 {} {} {}", f[0], f[1], f[2]);
    }
    let _ = writeln!(t, "POINT_DATA {}", labels.len());
    let _ = writeln!(t, "FIELD FieldData 1\nRegionId 1 {} int", labels.len());
    for _ in labels {
        t.push_str("0\n");
    }
    let _ = writeln!(t, "SCALARS {name} int 1\nLOOKUP_TABLE default");
    for l in labels {
        let _ = writeln!(t, "{l}");
    }
    std::fs::write(path, t).unwrap();
}

fn matrix(v: &serde_json::Value) -> Rigid {
    let m: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    Rigid::from_row_major(&m.try_into().unwrap())
}

/// The fused teeth of `out/report.json` are the phantom's, each registered near its truth (a
/// wrong FDI mapping would pair a crown with another tooth's CBCT mesh).
fn assert_fused_truth(out: &Path, ph: &Phantom, want: &[u8]) {
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let got: Vec<u8> = r["teeth"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["fdi"].as_u64().unwrap() as u8)
        .collect();
    assert_eq!(got, want, "{r}");
    for t in r["teeth"].as_array().unwrap() {
        let fdi = t["fdi"].as_u64().unwrap() as u8;
        let tre = ph.truth.teeth[&fdi].tre(&ph.truth.world_to_cbct, &matrix(&t["cbct_to_output"]));
        // Neighbouring teeth stand ~7 mm apart, so a crown paired with the wrong CBCT tooth
        // would be off by millimetres; the teeth-only fuse measures 0.35 mm at most here.
        println!("tooth {fdi}: TRE {tre:.3} mm");
        assert!(tre < 1.0, "tooth {fdi}: TRE {tre} mm");
        assert_eq!(t["watertight"], true, "tooth {fdi}");
    }
}

#[test]
fn teeth_only_universal_ios_is_read_and_fused() {
    let ph = Phantom::generate(&PhantomOptions {
        seed: 3,
        variant: Variant::PartialArch,
        ..Default::default()
    })
    .expect("phantom");
    let d = tmp("universal");
    let crowns = ph.ios_crowns();
    let cbct = d.join("cbct");
    write_teeth_dir(&cbct, &ph.cbct, "ply").unwrap();
    let uni = |f: u8| fdi_to_universal(f).unwrap();
    let (mesh, labels) = teeth_only(&crowns, uni);
    assert!(!labels.contains(&0), "teeth only: no gingiva label");
    let vtp = d.join("ios.vtp");
    let decoy: Vec<i32> = (0..labels.len() as i32).map(|i| i % 7).collect();
    write_vtp_file(
        &vtp,
        &mesh,
        &[("RegionId", &decoy), ("UniversalID", &labels)],
    );
    let vtk = d.join("ios.vtk");
    write_legacy_vtk(&vtk, &mesh, "UniversalID", &labels);
    let want: Vec<u8> = crowns
        .keys()
        .copied()
        .filter(|f| ph.cbct.contains_key(f))
        .collect();
    let mapping: Vec<String> = crowns.keys().map(|&f| format!("{}->{f}", uni(f))).collect();
    let mut sorted: Vec<(i32, u8)> = crowns.keys().map(|&f| (uni(f), f)).collect();
    sorted.sort_unstable();
    let mapping_sorted: Vec<String> = sorted.iter().map(|(u, f)| format!("{u}->{f}")).collect();
    assert_eq!(mapping.len(), mapping_sorted.len());
    for file in [&vtp, &vtk] {
        let info = ok(&["info", s(file)]);
        assert!(
            info.contains("label array: \"UniversalID\" (point data"),
            "{info}"
        );
        assert!(
            info.contains("numbering: universal (array name \"UniversalID\")"),
            "{info}"
        );
        assert!(
            info.contains(&format!("FDI: {}", mapping_sorted.join(" "))),
            "{info}"
        );
        let named = ok(&["info", s(file), "--label-array", "UniversalID"]);
        assert!(named.contains("numbering: universal"), "{named}");
    }
    // fuse: .vtp with the array found by name, .vtk with the array named on the command line.
    let out = d.join("fused_vtp");
    let log = ok(&[
        "fuse",
        "--ios",
        s(&vtp),
        "--cbct",
        s(&cbct),
        "--out",
        s(&out),
        "--frame",
        "ios",
    ]);
    assert!(log.contains("numbering universal"), "{log}");
    assert_fused_truth(&out, &ph, &want);
    let out = d.join("fused_vtk");
    ok(&[
        "fuse",
        "--ios",
        s(&vtk),
        "--ios-label-array",
        "UniversalID",
        "--cbct",
        s(&cbct),
        "--out",
        s(&out),
        "--frame",
        "ios",
    ]);
    assert_fused_truth(&out, &ph, &want);
    // A name the file does not hold: refused, listing the arrays it has.
    let e = fails(&[
        "fuse",
        "--ios",
        s(&vtk),
        "--ios-label-array",
        "PredictedID",
        "--cbct",
        s(&cbct),
        "--out",
        s(&out),
    ]);
    assert!(
        e.contains("\"PredictedID\"") && e.contains("\"RegionId\""),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ambiguous_or_missing_labels_are_refused_with_the_way_out() {
    let ph = Phantom::generate(&PhantomOptions {
        seed: 3,
        variant: Variant::Full,
        ..Default::default()
    })
    .expect("phantom");
    let d = tmp("ambiguous");
    // Upper-left teeth FDI 21..=26 are Universal 9..=14: written as Universal 11..=14 only
    // (FDI 23..=26), the values are valid FDI too (one jaw either way).
    let crowns: BTreeMap<u8, TriMesh> = ph
        .ios_crowns()
        .into_iter()
        .filter(|(f, _)| (23..=26).contains(f))
        .collect();
    assert!(!crowns.is_empty(), "phantom lacks teeth 23-26");
    let (mesh, labels) = teeth_only(&crowns, |f| fdi_to_universal(f).unwrap());
    assert!(labels.iter().all(|l| (11..=14).contains(l)));
    let generic = d.join("generic.vtp");
    write_vtp_file(&generic, &mesh, &[("Label", &labels)]);
    let info = ok(&["info", s(&generic)]);
    assert!(
        info.contains("ambiguous") && info.contains("--labels"),
        "{info}"
    );
    let info = ok(&["info", s(&generic), "--labels", "universal"]);
    let first = crowns.keys().next().unwrap();
    assert!(
        info.contains(&format!("{}->{first}", fdi_to_universal(*first).unwrap())),
        "{info}"
    );
    let named = d.join("named.vtp");
    write_vtp_file(&named, &mesh, &[("UniversalID", &labels)]);
    assert!(ok(&["info", s(&named)]).contains("numbering: universal"));
    let cbct = d.join("cbct");
    write_teeth_dir(&cbct, &ph.cbct, "ply").unwrap();
    let e = fails(&["register", "--ios", s(&generic), "--cbct", s(&cbct)]);
    assert!(e.contains("ambiguous") && e.contains(s(&generic)), "{e}");
    // CBCT as one mesh whose label array has a name no tool convention uses: refused with the
    // list of arrays, read with --cbct-label-array.
    let cbct_vtp = d.join("cbct.vtp");
    let (cm, cl) = teeth_only(&ph.cbct, i32::from);
    write_vtp_file(&cbct_vtp, &cm, &[("ToothNumber", &cl)]);
    let e = fails(&["register", "--ios", s(&named), "--cbct", s(&cbct_vtp)]);
    assert!(
        e.contains("\"ToothNumber\"") && e.contains("--cbct-label-array"),
        "{e}"
    );
    let report = d.join("report.json");
    let log = ok(&[
        "register",
        "--ios",
        s(&named),
        "--cbct",
        s(&cbct_vtp),
        "--cbct-label-array",
        "ToothNumber",
        "--out",
        s(&report),
    ]);
    assert!(
        log.contains("labels \"ToothNumber\", numbering fdi"),
        "{log}"
    );
    assert!(
        log.contains("labels \"UniversalID\", numbering universal"),
        "{log}"
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let got: Vec<u64> = r["teeth"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["fdi"].as_u64().unwrap())
        .collect();
    let want: Vec<u64> = crowns.keys().map(|&f| f as u64).collect();
    assert_eq!(
        got, want,
        "the UniversalID crowns pair with their FDI CBCT teeth"
    );
    // No label array: the arrays found are listed.
    let bare = d.join("bare.vtp");
    write_vtp_file(&bare, &mesh, &[("RegionId", &labels)]);
    let info = ok(&["info", s(&bare)]);
    assert!(
        info.contains("label array: none found") && info.contains("\"RegionId\""),
        "{info}"
    );
    let e = fails(&["register", "--ios", s(&bare), "--cbct", s(&cbct)]);
    assert!(
        e.contains("\"RegionId\"") && e.contains("--ios-label-array"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The two input files are read side by side; whichever fails is named, the IOS first when
/// both do.
#[test]
fn unreadable_inputs_are_named_ios_first() {
    let d = tmp("unreadable");
    let tetra = |label: i32| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty int label\nelement face 4\n\
             property list uchar int vertex_indices\nend_header\n\
             0 0 0 {label}\n1 0 0 {label}\n0 1 0 {label}\n0 0 1 {label}\n\
             3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
        )
    };
    let (good_ios, good_cbct) = (d.join("ios.ply"), d.join("cbct.ply"));
    std::fs::write(&good_ios, tetra(46)).unwrap();
    std::fs::write(&good_cbct, tetra(46)).unwrap();
    let (bad_ios, bad_cbct) = (d.join("bad_ios.ply"), d.join("bad_cbct.ply"));
    std::fs::write(
        &bad_ios,
        "ply\nformat ascii 1.0\nelement vertex 2\nend_header\n",
    )
    .unwrap();
    std::fs::write(&bad_cbct, "not a mesh at all\n").unwrap();
    let out = d.join("out");
    let fuse = |ios: &Path, cbct: &Path| {
        fails(&["fuse", "--ios", s(ios), "--cbct", s(cbct), "--out", s(&out)])
    };
    let e = fuse(&bad_ios, &bad_cbct);
    assert!(e.contains("reading IOS") && e.contains(s(&bad_ios)), "{e}");
    let e = fuse(&bad_ios, &good_cbct);
    assert!(e.contains("reading IOS") && e.contains(s(&bad_ios)), "{e}");
    let e = fuse(&good_ios, &bad_cbct);
    assert!(
        e.contains("reading CBCT") && e.contains(s(&bad_cbct)),
        "{e}"
    );
    assert!(!out.exists(), "nothing written on a read error");
}
