//! toothfuse's point-to-plane ICP on point sets shared with Open3D (`benches/compare/run.sh`).
//!
//! `icp_compare export DIR [FOREIGN_CASE_DIR ...]` writes, per tooth of the synthetic jaw (seed 1,
//! upper, full arch) and of each foreign case, the IOS crown and the CBCT tooth as raw
//! little-endian arrays plus `DIR/manifest.json`: `source.f64` (the IOS crown vertices the ICP
//! iterates on, IOS frame), `cbct_vertices.f64` with `target_normals.f64` (the CBCT tooth's
//! vertices and the normals toothfuse pairs them with, CBCT frame), `eval.f64` (the points the
//! TRE is measured over, CBCT frame: the true tooth surface of the synthetic jaw, the CBCT tooth
//! of a foreign case), `initial.f64` (the shared initial IOS → CBCT pose, 4×4 row-major: the true
//! pose moved by a fixed 4° and 0.78 mm), and the meshes toothfuse reads back.
//!
//! `icp_compare run DIR RESULT_JSON` reads those files back and runs, per tooth, the library's
//! eq. (3) stage ([`register`] with one tooth, no coarse stage) as plain point-to-plane ICP: IOS
//! source, CBCT target, closest vertex, CBCT normals, unit weights, pairs farther apart than the
//! manifest's distance dropped, the manifest's iteration count with convergence tests disabled.
//! It writes each estimate and its timing (`loop_ms`: the ICP iterations; `call_ms`: the same
//! plus building the tooth's closest-point index).
use glam::DVec3;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use toothfuse::phantom::{Phantom, PhantomOptions};
use toothfuse::register::{
    Convergence, Correspondence, FineMode, RegisterOptions, StageOptions, WeightOptions, register,
};
use toothfuse::{Rigid, TriMesh};

/// ICP iterations both libraries run.
const ITERATIONS: usize = 30;
/// Pairs farther apart than this are dropped by both libraries (mm).
const MAX_CORRESPONDENCE_MM: f64 = 2.0;

/// One tooth as both sides see it.
struct ToothCase {
    fdi: u8,
    ios: TriMesh,
    cbct: TriMesh,
    eval: Vec<DVec3>,
    truth_cbct_to_ios: Rigid,
}

fn write_points(path: &Path, pts: &[DVec3]) {
    let bytes: Vec<u8> = pts
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f64::to_le_bytes)
        .collect();
    fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn write_triangles(path: &Path, tris: &[[u32; 3]]) {
    let bytes: Vec<u8> = tris
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn read_bytes(path: &Path) -> Vec<u8> {
    fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn read_f64(path: &Path) -> Vec<f64> {
    read_bytes(path)
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

fn read_points(path: &Path) -> Vec<DVec3> {
    read_f64(path)
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}

fn read_triangles(path: &Path) -> Vec<[u32; 3]> {
    let v: Vec<u32> = read_bytes(path)
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// The synthetic jaw: every tooth in both modalities, TRE over the true tooth surface.
fn phantom_teeth() -> Vec<ToothCase> {
    let p = Phantom::generate(&PhantomOptions::default()).expect("phantom");
    let crowns = p.ios_crowns();
    let to_cbct = p.truth.world_to_cbct;
    crowns
        .into_iter()
        .filter_map(|(fdi, ios)| {
            let cbct = p.cbct.get(&fdi)?.clone();
            let t = &p.truth.teeth[&fdi];
            Some(ToothCase {
                fdi,
                ios,
                cbct,
                eval: t
                    .surface
                    .positions
                    .iter()
                    .map(|&w| to_cbct.apply(w))
                    .collect(),
                truth_cbct_to_ios: t.cbct_to_ios,
            })
        })
        .collect()
}

/// A foreign case (`ios.ply`, `cbct.ply`, `truth/transforms.json`): TRE over the CBCT tooth.
fn foreign_teeth(dir: &Path) -> Vec<ToothCase> {
    let ios = toothfuse::io::read_teeth(dir.join("ios.ply")).expect("foreign ios.ply");
    let cbct = toothfuse::io::read_teeth(dir.join("cbct.ply")).expect("foreign cbct.ply");
    let truth: Value = serde_json::from_slice(&read_bytes(&dir.join("truth/transforms.json")))
        .expect("transforms.json");
    ios.into_iter()
        .filter_map(|(fdi, crown)| {
            let tooth = cbct.get(&fdi)?.clone();
            let rows = truth["ios_from_cbct"][fdi.to_string()].as_array()?;
            let m: Vec<f64> = rows
                .iter()
                .flat_map(|r| r.as_array().expect("matrix row").iter())
                .map(|x| x.as_f64().expect("matrix entry"))
                .collect();
            Some(ToothCase {
                fdi,
                ios: crown,
                eval: tooth.positions.clone(),
                cbct: tooth,
                truth_cbct_to_ios: Rigid::from_row_major(&m.try_into().expect("4x4")),
            })
        })
        .collect()
}

/// The shared initial IOS → CBCT pose: the true one, then 4° about a fixed axis through the
/// CBCT tooth's vertex centroid and a 0.78 mm shift.
fn initial_pose(t: &ToothCase) -> Rigid {
    let c = t.cbct.positions.iter().copied().sum::<DVec3>() / t.cbct.positions.len() as f64;
    let turn = Rigid::from_axis_angle_about(DVec3::new(1.0, 2.0, 3.0), 4f64.to_radians(), c);
    Rigid::from_translation(DVec3::new(0.6, -0.4, 0.3))
        .compose(&turn)
        .compose(&t.truth_cbct_to_ios.inverse())
        .orthonormalized()
}

fn export(dir: &Path, foreign: &[PathBuf]) {
    let mut cases = vec![("phantom_seed1_upper".to_string(), phantom_teeth())];
    for f in foreign {
        let name = f
            .file_name()
            .expect("case folder")
            .to_string_lossy()
            .into_owned();
        cases.push((name, foreign_teeth(f)));
    }
    let mut out = Vec::new();
    for (name, teeth) in &cases {
        let mut rows = Vec::new();
        for t in teeth {
            let rel = format!("{name}/tooth_{}", t.fdi);
            let d = dir.join(&rel);
            fs::create_dir_all(&d).expect("create tooth folder");
            // The source points are the crown vertices with a normal: the ones `register` uses.
            let source: Vec<DVec3> = t
                .ios
                .positions
                .iter()
                .zip(t.ios.vertex_normals())
                .filter(|(_, n)| *n != DVec3::ZERO)
                .map(|(p, _)| *p)
                .collect();
            write_points(&d.join("source.f64"), &source);
            write_points(&d.join("ios_vertices.f64"), &t.ios.positions);
            write_triangles(&d.join("ios_triangles.u32"), &t.ios.triangles);
            write_points(&d.join("cbct_vertices.f64"), &t.cbct.positions);
            write_triangles(&d.join("cbct_triangles.u32"), &t.cbct.triangles);
            write_points(&d.join("target_normals.f64"), &t.cbct.vertex_normals());
            write_points(&d.join("eval.f64"), &t.eval);
            let init = initial_pose(t).to_row_major();
            let bytes: Vec<u8> = init.iter().flat_map(|x| x.to_le_bytes()).collect();
            fs::write(d.join("initial.f64"), bytes).expect("write initial.f64");
            rows.push(json!({
                "fdi": t.fdi,
                "dir": rel,
                "source_points": source.len(),
                "target_points": t.cbct.positions.len(),
                "truth_cbct_to_ios": t.truth_cbct_to_ios.to_row_major().to_vec(),
            }));
        }
        out.push(json!({ "name": name, "teeth": rows }));
    }
    let manifest = json!({
        "iterations": ITERATIONS,
        "max_correspondence_mm": MAX_CORRESPONDENCE_MM,
        "cases": out,
    });
    fs::write(
        dir.join("manifest.json"),
        serde_json::to_string_pretty(&manifest).expect("json"),
    )
    .expect("write manifest.json");
}

/// Plain point-to-plane ICP with the library's fine stage: one tooth, IOS source, CBCT target.
fn icp_options(initial_ios_to_cbct: Rigid) -> RegisterOptions {
    let stage = StageOptions {
        correspondence: Correspondence::ClosestVertex,
        weights: WeightOptions {
            max_distance_mm: MAX_CORRESPONDENCE_MM,
            ..WeightOptions::PLAIN
        },
        // Negative thresholds are never met: every one of the iterations runs.
        convergence: Convergence {
            max_iterations: ITERATIONS,
            step_mm: -1.0,
            relative_rms: -1.0,
        },
        subsample: false,
        full_resolution_iterations: 0,
        warmup: false,
        estimate_offset: false,
        source_normals: false,
    };
    RegisterOptions {
        initial: Some(initial_ios_to_cbct.inverse()),
        coarse: None,
        fine: FineMode::Sequential(stage),
        report_points: 1,
        ..RegisterOptions::paper()
    }
}

fn run(dir: &Path, result: &Path) {
    let manifest: Value =
        serde_json::from_slice(&read_bytes(&dir.join("manifest.json"))).expect("manifest.json");
    let mut cases = Vec::new();
    for case in manifest["cases"].as_array().expect("cases") {
        let mut rows = Vec::new();
        for tooth in case["teeth"].as_array().expect("teeth") {
            let fdi = tooth["fdi"].as_u64().expect("fdi") as u8;
            let d = dir.join(tooth["dir"].as_str().expect("dir"));
            let mesh = |v: &str, t: &str| {
                TriMesh::new(read_points(&d.join(v)), read_triangles(&d.join(t)))
            };
            let ios = BTreeMap::from([(fdi, mesh("ios_vertices.f64", "ios_triangles.u32"))]);
            let cbct = BTreeMap::from([(fdi, mesh("cbct_vertices.f64", "cbct_triangles.u32"))]);
            let init: [f64; 16] = read_f64(&d.join("initial.f64")).try_into().expect("4x4");
            let r = register(&ios, &cbct, &icp_options(Rigid::from_row_major(&init)))
                .unwrap_or_else(|e| panic!("{} tooth {fdi}: {e}", case["name"]));
            let t = &r.teeth[&fdi];
            rows.push(json!({
                "fdi": fdi,
                "ios_to_cbct": t.cbct_to_ios.inverse().to_row_major().to_vec(),
                "iterations": t.iterations,
                "loop_ms": r.timing.fine_ms,
                "call_ms": r.timing.prepare_ms + r.timing.fine_ms,
            }));
        }
        cases.push(json!({ "name": case["name"], "teeth": rows }));
    }
    let out = json!({ "cases": cases });
    fs::write(result, serde_json::to_string_pretty(&out).expect("json")).expect("write result");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["export", dir, foreign @ ..] => {
            let foreign: Vec<PathBuf> = foreign.iter().map(PathBuf::from).collect();
            export(Path::new(dir), &foreign)
        }
        ["run", dir, result] => run(Path::new(dir), Path::new(result)),
        _ => {
            eprintln!(
                "usage: icp_compare export DIR [FOREIGN_CASE_DIR ...] | icp_compare run DIR RESULT_JSON"
            );
            std::process::exit(2);
        }
    }
}
