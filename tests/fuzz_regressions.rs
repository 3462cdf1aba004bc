//! The fuzz corpus as plain tests: every seed of `fuzz/seeds/<reader>/` reads as a valid mesh,
//! and every input a fuzz target once crashed on (`tests/fuzz_regressions/<reader>/`, kept after
//! the fix) ends as an error naming the file or as a mesh keeping the readers' promises, without
//! panicking or allocating what a header merely declares. The targets themselves run in scripts/check_fuzz.sh.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use toothfuse::io;
use toothfuse::mesh::LabeledMesh;

/// The system allocator, recording the largest single request: a reader must size its buffers by
/// the bytes it was given, never by a count a header merely declares.
struct LargestAlloc;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged.
unsafe impl GlobalAlloc for LargestAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        // SAFETY: the caller's contract, forwarded.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, forwarded.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        // SAFETY: the caller's contract, forwarded.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: LargestAlloc = LargestAlloc;

/// Largest single allocation allowed while reading inputs of a few KB.
const ALLOC_LIMIT: usize = 64 << 20;

const READERS: [&str; 5] = [
    "read_ply",
    "read_stl",
    "read_obj_labels",
    "read_vtp",
    "read_vtk_legacy",
];

/// Reads `data` the way fuzz target `target` does (OBJ: label JSON after a NUL byte).
fn read(target: &str, data: &[u8]) -> toothfuse::Result<LabeledMesh> {
    match target {
        "read_ply" => io::read_ply_bytes("input", data),
        "read_stl" => io::read_stl_bytes("input", data).map(|mesh| LabeledMesh {
            mesh,
            ..Default::default()
        }),
        "read_obj_labels" => match data.iter().position(|&b| b == 0) {
            Some(i) => {
                io::read_obj_labeled_bytes("input", &data[..i], Some(("labels", &data[i + 1..])))
            }
            None => io::read_obj_labeled_bytes("input", data, None),
        },
        "read_vtp" => io::read_vtp_bytes("input", data),
        "read_vtk_legacy" => io::read_vtk_legacy_bytes("input", data),
        _ => unreachable!("unknown target {target}"),
    }
}

/// The files of a folder, sorted (none when it does not exist).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    v.retain(|p| p.is_file());
    v.sort();
    v
}

/// What every successful read promises (as the fuzz targets assert).
fn check_invariants(what: &str, m: &LabeledMesh) {
    let n = m.mesh.positions.len();
    assert!(m.mesh.positions.iter().all(|p| p.is_finite()), "{what}");
    assert!(
        m.mesh.triangles.iter().flatten().all(|&v| (v as usize) < n),
        "{what}: index out of range"
    );
    if let Some(l) = &m.vertex_labels {
        assert_eq!(l.len(), n, "{what}: vertex labels");
    }
    if let Some(l) = &m.face_labels {
        assert_eq!(l.len(), m.mesh.triangles.len(), "{what}: face labels");
    }
}

#[test]
fn every_seed_reads_as_a_valid_mesh() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for target in READERS {
        let seeds = files(&root.join("fuzz/seeds").join(target));
        assert!(seeds.len() >= 2, "{target}: seed corpus missing");
        for f in seeds {
            let what = format!("{target} seed {}", f.display());
            let m =
                read(target, &std::fs::read(&f).unwrap()).unwrap_or_else(|e| panic!("{what}: {e}"));
            check_invariants(&what, &m);
            // Every seed is the same labeled square pyramid: 5 vertices, 6 triangles.
            assert_eq!(
                (m.mesh.positions.len(), m.mesh.triangles.len()),
                (5, 6),
                "{what}"
            );
        }
    }
}

#[test]
fn every_fuzz_crash_input_is_read_or_refused_cleanly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut n = 0;
    for target in READERS {
        for f in files(&root.join(target)) {
            let data = std::fs::read(&f).unwrap();
            let result = read(target, &data);
            let largest = LARGEST.load(Ordering::Relaxed);
            assert!(
                largest <= ALLOC_LIMIT,
                "{}: an allocation of {largest} bytes for a {}-byte input",
                f.display(),
                data.len()
            );
            match result {
                Err(e) => {
                    let msg = e.to_string();
                    assert!(msg.contains("input: "), "{}: {msg}", f.display());
                    println!("{target} {}: {msg}", f.display());
                }
                // Some crash inputs are valid once the crash is fixed (e.g. points and no
                // cells): they must then satisfy the reader's promises.
                Ok(m) => {
                    check_invariants(&f.display().to_string(), &m);
                    println!(
                        "{target} {}: read, {} vertices",
                        f.display(),
                        m.mesh.positions.len()
                    );
                }
            }
            n += 1;
        }
    }
    assert!(n >= 2, "regression inputs missing");
    println!("{n} regression inputs handled");
}
