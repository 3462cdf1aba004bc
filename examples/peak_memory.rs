//! Peak heap and wall time of the whole library fuse (`pipeline::fuse`: split, register, cut,
//! stitch) on each input of the `stages` benchmark (clean phantom 1x, rough 1x, 2x, 4x, the
//! foreign jaws when present), with a counting global allocator (the system allocator wrapped
//! to track the bytes in use and their peak). Prints a markdown table: input, IOS vertex count,
//! fused teeth, wall ms (median of 3 runs), heap held before the fuse (the inputs), peak heap
//! during the fuse (inputs included) and the fuse's own peak above what was held. MB = 10^6
//! bytes. The allocator's counting adds a little time; criterion (`benches/stages.rs`) is the
//! reference for speed.
//!
//! `cargo run --release --example peak_memory` (`STAGES_INPUTS=clean_1x,f901_upper` for a
//! subset). With `--stages DIR` it prints instead the per-stage criterion medians found in
//! `DIR` (normally `target/criterion`, after `cargo bench -p toothfuse-benches --bench stages`), one column per
//! input: the README's speed table (see `benches/table.sh`).

#[path = "../benches/common/inputs.rs"]
mod inputs;

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;
use toothfuse::pipeline::{self, PipelineOptions};

/// The system allocator, counting the bytes in use and their peak.
struct Counting;

/// Bytes currently allocated.
static CURRENT: AtomicUsize = AtomicUsize::new(0);
/// Highest [`CURRENT`] since the last [`reset_peak`].
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(n: usize) {
    let now = CURRENT.fetch_add(n, Ordering::Relaxed) + n;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

fn shrank(n: usize) {
    CURRENT.fetch_sub(n, Ordering::Relaxed);
}

// SAFETY: every call is forwarded unchanged to `System`, which upholds the `GlobalAlloc`
// contract; the counters only observe the sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded contract of `GlobalAlloc::alloc`.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded contract of `GlobalAlloc::alloc_zeroed`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded contract of `GlobalAlloc::dealloc`.
        unsafe { System.dealloc(ptr, layout) };
        shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded contract of `GlobalAlloc::realloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grew(new_size - layout.size());
            } else {
                shrank(layout.size() - new_size);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Restarts the peak at the bytes now in use.
fn reset_peak() {
    PEAK.store(CURRENT.load(Ordering::Relaxed), Ordering::Relaxed);
}

fn mb(bytes: usize) -> f64 {
    bytes as f64 / 1e6
}

/// The memory table: one row per input, each input loaded, fused three times and dropped
/// before the next is loaded.
fn memory_table() {
    println!(
        "| input | IOS vertices | fused teeth | whole fuse wall ms (median of 3) | heap held before (MB) | peak heap during fuse (MB) | fuse's own peak (MB) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let opts = PipelineOptions::default();
    for (name, source) in inputs::selected() {
        let Some(input) = inputs::load(name, source) else {
            println!("| {name} | absent: skipped | | | | | |");
            continue;
        };
        let held = CURRENT.load(Ordering::Relaxed);
        let (mut times, mut peak, mut teeth) = (Vec::new(), 0, 0);
        for _ in 0..3 {
            reset_peak();
            let t0 = Instant::now();
            let r = pipeline::fuse(&input.ios, &input.cbct, &opts).expect("fuse");
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            teeth = r.jaw.teeth.len();
            drop(r);
            peak = peak.max(PEAK.load(Ordering::Relaxed));
        }
        times.sort_by(f64::total_cmp);
        println!(
            "| {name} | {} | {teeth} | {:.0} | {:.1} | {:.1} | {:.1} |",
            input.ios_vertices(),
            times[1],
            mb(held),
            mb(peak),
            mb(peak.saturating_sub(held)),
        );
    }
}

/// Stages of the `stages` benchmark in pipeline order, with their table labels.
const STAGES: [(&str, &str); 18] = [
    ("read_ios", "read IOS (binary PLY)"),
    ("read_cbct", "read CBCT (binary PLY)"),
    ("split", "label split into crowns"),
    ("normals", "vertex normals (1 thread)"),
    ("kdtree", "k-d trees + CBCT normals (1 thread)"),
    (
        "reg_prepare",
        "register: prepare (normals, k-d trees, checks)",
    ),
    ("reg_gate", "register: gate"),
    ("reg_centroid", "register: centroid alignment (CA)"),
    ("reg_coarse", "register: coarse (CR)"),
    ("reg_fine", "register: fine + drift smoothing (FR)"),
    ("reg_report", "register: report (SD, checks)"),
    ("register", "register (whole)"),
    ("cut", "crown cut"),
    ("stitch", "stitch (band, untangle, quality)"),
    ("quality", "quality report again (1 thread)"),
    ("report_json", "report.json text"),
    ("write", "write fused.ply, tooth_*.ply, report.json"),
    ("fuse", "**whole fuse** (split + register + cut + stitch)"),
];

/// Median (ms) of one criterion benchmark, from `DIR/<group>/<function>/new/estimates.json`.
fn median_ms(dir: &Path, group: &str, function: &str) -> Option<f64> {
    let p = dir.join(group).join(function).join("new/estimates.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
    Some(v["median"]["point_estimate"].as_f64()? / 1e6)
}

fn fmt_ms(ms: f64) -> String {
    if ms < 1.0 {
        format!("{ms:.2}")
    } else if ms < 10.0 {
        format!("{ms:.1}")
    } else {
        format!("{ms:.0}")
    }
}

/// The per-stage table of criterion medians (ms), one column per input benchmarked.
fn stage_table(dir: &Path) {
    let names: Vec<&str> = inputs::ALL
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| median_ms(dir, &format!("stages_{n}"), "fuse").is_some())
        .collect();
    if names.is_empty() {
        eprintln!(
            "no stages_* results in {} (run cargo bench -p toothfuse-benches --bench stages)",
            dir.display()
        );
        std::process::exit(1);
    }
    println!("| stage (criterion median, ms) | {} |", names.join(" | "));
    println!("|---|{}", "---|".repeat(names.len()));
    for (id, label) in &STAGES {
        let cells: Vec<String> = names
            .iter()
            .map(|n| median_ms(dir, &format!("stages_{n}"), id).map_or("—".into(), fmt_ms))
            .collect();
        println!("| {label} | {} |", cells.join(" | "));
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.as_slice() {
        [] => memory_table(),
        [flag, dir] if flag == "--stages" => stage_table(Path::new(dir)),
        _ => {
            eprintln!("usage: peak_memory [--stages target/criterion]");
            std::process::exit(2);
        }
    }
}
