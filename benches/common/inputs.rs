//! The deterministic inputs of the `stages` benchmark and the `peak_memory` example: the
//! project's phantom jaw (seed 1, upper, full arch) as the clean scan and as rough exports at
//! 1x, 2x and 4x the vertex density, and the two foreign jaws of `shared/data/foreign/` read
//! with the library's readers (skipped, with a message, when they are absent).
//!
//! Included with `#[path]` by both targets (it lives in a subfolder so Cargo does not take it
//! for a benchmark of its own).

// Each including target uses a different part of this module.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::mesh::LabeledMesh;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions};

/// One benchmark input: a labelled IOS jaw and CBCT teeth, as a host hands them over.
pub struct Input {
    /// Short name used in benchmark ids and table rows (`clean_1x`, `f901_upper`, ...).
    pub name: String,
    /// The IOS jaw with per-vertex FDI labels (0 = gingiva), IOS frame.
    pub ios: LabeledMesh,
    /// Closed CBCT tooth meshes by FDI, CBCT frame.
    pub cbct: BTreeMap<u8, TriMesh>,
    /// The files the input was read from (`ios.ply`, `cbct.ply`), for the foreign jaws.
    pub files: Option<(PathBuf, PathBuf)>,
}

impl Input {
    /// Vertex count of the IOS jaw (crowns and gingiva).
    pub fn ios_vertices(&self) -> usize {
        self.ios.mesh.positions.len()
    }
}

/// Where an input comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source {
    /// The default phantom with this IOS export.
    Phantom(IosExport),
    /// A foreign jaw (case folder name).
    Foreign(&'static str),
}

/// Every input, by name: the clean scan (1x), the rough exports at 1x, 2x and 4x the vertex
/// density, and the two foreign jaws.
pub const ALL: [(&str, Source); 6] = [
    ("clean_1x", Source::Phantom(IosExport::Clean)),
    ("rough_1x", Source::Phantom(IosExport::Rough)),
    ("dense2_2x", Source::Phantom(IosExport::Dense2)),
    ("dense4_4x", Source::Phantom(IosExport::Dense4)),
    ("f901_upper", Source::Foreign("f901_upper")),
    ("f902_lower", Source::Foreign("f902_lower")),
];

/// The inputs to run: all of [`ALL`], or those named in `$STAGES_INPUTS` (comma-separated).
pub fn selected() -> Vec<(&'static str, Source)> {
    let only = std::env::var("STAGES_INPUTS").ok();
    ALL.iter()
        .copied()
        .filter(|(n, _)| {
            only.as_deref()
                .is_none_or(|o| o.split(',').any(|x| x.trim() == *n))
        })
        .collect()
}

/// Loads an input; `None` (with a message) for a foreign jaw that is absent.
pub fn load(name: &str, source: Source) -> Option<Input> {
    match source {
        Source::Phantom(e) => Some(phantom(name, e)),
        Source::Foreign(case) => foreign(case),
    }
}

/// The default phantom (seed 1, upper full arch) with the IOS exported as `export`; only the
/// inputs are kept (the truth is dropped).
pub fn phantom(name: &str, export: IosExport) -> Input {
    let mut opts = PhantomOptions::default();
    opts.realism.ios.rough = export.roughness();
    let p = Phantom::generate(&opts).expect("phantom generation");
    Input {
        name: name.to_string(),
        ios: p.ios,
        cbct: p.cbct,
        files: None,
    }
}

/// The folder of the foreign jaws: `$TOOTHFUSE_FOREIGN_DATA`, else `shared/data/foreign` beside
/// the checkout or beside its parent (a worktree), else `/work/shared/data/foreign`.
pub fn foreign_dir() -> Option<PathBuf> {
    // The repository root: this crate is its benches/ folder.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut candidates: Vec<PathBuf> = std::env::var_os("TOOTHFUSE_FOREIGN_DATA")
        .map(PathBuf::from)
        .into_iter()
        .collect();
    candidates.push(root.join("../shared/data/foreign"));
    candidates.push(root.join("../../shared/data/foreign"));
    candidates.push(PathBuf::from("/work/shared/data/foreign"));
    candidates.into_iter().find(|d| d.is_dir())
}

/// A foreign jaw read with the library's readers (`io::read_mesh` for the labelled IOS,
/// `io::read_teeth` for the labelled CBCT mesh; both FDI-numbered), or `None` with a message on
/// stderr when the data is absent.
pub fn foreign(case: &str) -> Option<Input> {
    let Some(dir) = foreign_dir() else {
        eprintln!(
            "SKIPPED foreign jaw {case}: shared/data/foreign not found (set TOOTHFUSE_FOREIGN_DATA)"
        );
        return None;
    };
    let (ios_path, cbct_path) = (
        dir.join(case).join("ios.ply"),
        dir.join(case).join("cbct.ply"),
    );
    if !ios_path.is_file() || !cbct_path.is_file() {
        eprintln!(
            "SKIPPED foreign jaw {case}: {} absent",
            dir.join(case).display()
        );
        return None;
    }
    let ios = toothfuse::io::read_mesh(&ios_path).expect("foreign IOS");
    let cbct = toothfuse::io::read_teeth(&cbct_path).expect("foreign CBCT");
    Some(Input {
        name: case.to_string(),
        ios,
        cbct,
        files: Some((ios_path, cbct_path)),
    })
}
