//! Every stage of a whole-jaw fuse, and the whole one-call fuse, on deterministic inputs: the
//! default phantom as the clean scan (1x) and as rough exports at 1x, 2x and 4x the vertex
//! density, and the two foreign jaws (skipped with a message when absent). One criterion group
//! per input (`stages_<input>`), one function per stage:
//!
//! - `read_ios`, `read_cbct`: the library's readers on binary PLY (the phantom's files are
//!   written to a temporary folder first; the foreign jaws' are read in place);
//! - `split`: the labelled IOS jaw split into crowns (`fuse::ios_crowns`);
//! - `normals`: area-weighted vertex normals of every crown and CBCT tooth (one thread);
//! - `kdtree`: the closest-point index of every CBCT tooth (`register::correspondence::
//!   SurfaceIndex`: k-d tree, vertex and face normals, vertex → faces; one thread);
//! - `reg_prepare`, `reg_gate`, `reg_centroid` (CA), `reg_coarse` (CR), `reg_fine` (FR with the
//!   smooth-drift model of the default preset), `reg_report`: the stage timers of
//!   `register::register` (its `Timing`), read from whole registrations run back to back
//!   (criterion's `iter_custom`: only that stage's time is counted; the prepare stage builds the
//!   same normals and indices as above, on the teeth in parallel); `register`: the whole call;
//! - `cut`: crown removal of every tooth (`fuse::cut_jaw`) with the registered transforms;
//! - `stitch`: band, assembly, untangling and quality of every tooth (`fuse::stitch_jaw`);
//! - `quality`: the quality report of every fused tooth again (`fuse::quality::measure`, one
//!   thread; inside `stitch` it runs per tooth in parallel);
//! - `report_json`: the output contract's `report.json` text;
//! - `write`: the outputs of `toothfuse fuse` (fused.ply, tooth_<fdi>.ply, report.json);
//! - `fuse`: the whole library fuse from the labelled jaw (`pipeline::fuse`: split, register,
//!   cut, stitch), what `toothfuse fuse` runs between reading and writing.
//!
//! `cargo bench -p toothfuse-benches --bench stages` (a few minutes; the foreign jaws' stitching takes seconds per
//! run); `cargo bench -p toothfuse-benches --bench stages -- 'stages_clean_1x/'` for one input or `-- /stitch` for one
//! stage; `STAGES_INPUTS=clean_1x,f901_upper` generates or reads only those inputs.
//! `benches/table.sh` turns the medians into the README table.

#[path = "common/inputs.rs"]
mod inputs;

use criterion::{Criterion, criterion_group, criterion_main};
use inputs::Input;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;
use toothfuse::TriMesh;
use toothfuse::fuse::{cut_jaw, ios_crowns, quality, stitch_jaw};
use toothfuse::pipeline::{self, PipelineOptions, PipelineResult, PipelineTiming, transforms_of};
use toothfuse::register::correspondence::SurfaceIndex;
use toothfuse::register::{Timing, register};

/// Reads one stage's time (ms) from a registration's [`Timing`].
type StageTime = fn(&Timing) -> f64;

/// The registration stages read from [`Timing`], by benchmark name.
const REGISTER_STAGES: [(&str, StageTime); 6] = [
    ("reg_prepare", |t| t.prepare_ms),
    ("reg_gate", |t| t.gate_ms),
    ("reg_centroid", |t| t.centroid_ms),
    ("reg_coarse", |t| t.coarse_ms),
    ("reg_fine", |t| t.fine_ms),
    ("reg_report", |t| t.report_ms),
];

fn bench(c: &mut Criterion) {
    let tmp = std::env::temp_dir().join(format!("toothfuse-stages-{}", std::process::id()));
    for (name, source) in inputs::selected() {
        let Some(input) = inputs::load(name, source) else {
            continue;
        };
        bench_input(c, &input, &tmp.join(name));
    }
    // Best effort: a leftover temporary folder is harmless.
    let _ = std::fs::remove_dir_all(&tmp);
}

/// Writes the phantom's inputs as binary PLY (IOS with its `label`s, the CBCT teeth as one mesh
/// labelled by FDI, as the foreign jaws come) and returns the two paths.
fn write_inputs(input: &Input, dir: &Path) -> (PathBuf, PathBuf) {
    let ios = dir.join("ios.ply");
    let labels = input.ios.vertex_labels.as_deref().expect("vertex labels");
    toothfuse::io::write_mesh(&ios, &input.ios.mesh, &[("label", labels)]).expect("write IOS");
    let mut teeth = TriMesh::default();
    let mut tooth_labels = Vec::new();
    for (&fdi, m) in &input.cbct {
        teeth.append(m);
        tooth_labels.extend(std::iter::repeat_n(fdi as i32, m.positions.len()));
    }
    let cbct = dir.join("cbct.ply");
    toothfuse::io::write_mesh(&cbct, &teeth, &[("label", &tooth_labels)]).expect("write CBCT");
    (ios, cbct)
}

/// The outputs `toothfuse fuse` writes: `fused.ply` (labels and sources), `tooth_<fdi>.ply`
/// (sources) and `report.json`.
fn write_outputs(r: &PipelineResult, dir: &Path) {
    let source: Vec<i32> = r.jaw.source.iter().map(|&s| s as i32).collect();
    toothfuse::io::write_mesh(
        dir.join("fused.ply"),
        &r.jaw.mesh,
        &[("label", &r.jaw.labels), ("source", &source)],
    )
    .expect("write fused");
    for (fdi, t) in &r.jaw.teeth {
        let src: Vec<i32> = t.source.iter().map(|&s| s as i32).collect();
        toothfuse::io::write_mesh(
            dir.join(format!("tooth_{fdi}.ply")),
            &t.mesh,
            &[("source", &src)],
        )
        .expect("write tooth");
    }
    std::fs::write(dir.join("report.json"), r.to_json()).expect("write report");
}

fn bench_input(c: &mut Criterion, input: &Input, dir: &Path) {
    std::fs::create_dir_all(dir).expect("temporary folder");
    let opts = PipelineOptions::default();
    let mut ro = opts.register.clone();
    ro.frame = opts.frame;
    // One pass through the stages gives each later stage its input.
    let crowns = ios_crowns(&input.ios).expect("crowns");
    let registration = register(&crowns, &input.cbct, &ro).expect("register");
    let transforms = transforms_of(&registration);
    let cut = cut_jaw(&input.ios, &input.cbct, &transforms, &opts.fuse).expect("cut");
    let jaw = stitch_jaw(&cut, &opts.fuse);
    eprintln!(
        "{}: {} IOS vertices, {} crowns, {} CBCT teeth ({} vertices); {} fused, {} failed",
        input.name,
        input.ios_vertices(),
        crowns.len(),
        input.cbct.len(),
        input
            .cbct
            .values()
            .map(|m| m.positions.len())
            .sum::<usize>(),
        jaw.teeth.len(),
        jaw.failed.len()
    );
    let result = PipelineResult {
        registration,
        jaw,
        timing: PipelineTiming::default(),
    };
    let (ios_file, cbct_file) = match &input.files {
        Some(files) => files.clone(),
        None => write_inputs(input, dir),
    };
    let out = dir.join("out");
    std::fs::create_dir_all(&out).expect("output folder");

    let mut g = c.benchmark_group(format!("stages_{}", input.name));
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    g.bench_function("read_ios", |b| {
        b.iter(|| toothfuse::io::read_mesh(&ios_file).expect("read IOS"))
    });
    g.bench_function("read_cbct", |b| {
        b.iter(|| toothfuse::io::read_teeth(&cbct_file).expect("read CBCT"))
    });
    g.bench_function("split", |b| {
        b.iter(|| ios_crowns(black_box(&input.ios)).expect("split"))
    });
    let meshes: Vec<&TriMesh> = crowns.values().chain(input.cbct.values()).collect();
    g.bench_function("normals", |b| {
        b.iter(|| {
            meshes
                .iter()
                .map(|m| m.vertex_normals())
                .collect::<Vec<_>>()
        })
    });
    g.bench_function("kdtree", |b| {
        b.iter(|| {
            input
                .cbct
                .values()
                .map(|m| SurfaceIndex::new(m).expect("index"))
                .collect::<Vec<_>>()
        })
    });
    for (stage, time_of) in REGISTER_STAGES {
        g.bench_function(stage, |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| {
                        let r = register(&crowns, &input.cbct, &ro).expect("register");
                        Duration::from_secs_f64(time_of(&r.timing) / 1e3)
                    })
                    .sum()
            })
        });
    }
    g.bench_function("register", |b| {
        b.iter(|| register(black_box(&crowns), &input.cbct, &ro).expect("register"))
    });
    g.bench_function("cut", |b| {
        b.iter(|| cut_jaw(&input.ios, &input.cbct, &transforms, &opts.fuse).expect("cut"))
    });
    g.bench_function("stitch", |b| {
        b.iter(|| stitch_jaw(black_box(&cut), &opts.fuse))
    });
    g.bench_function("quality", |b| {
        b.iter(|| {
            result
                .jaw
                .teeth
                .values()
                .map(|t| {
                    let check = opts.fuse.check_self_intersections;
                    quality::measure(&t.mesh, t.band_faces.clone(), check)
                })
                .collect::<Vec<_>>()
        })
    });
    g.bench_function("report_json", |b| b.iter(|| result.to_json()));
    g.bench_function("write", |b| b.iter(|| write_outputs(&result, &out)));
    g.bench_function("fuse", |b| {
        b.iter(|| pipeline::fuse(black_box(&input.ios), &input.cbct, &opts).expect("fuse"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
