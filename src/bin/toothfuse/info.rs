//! `toothfuse info`: facts about a mesh file, whole and per label.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::mesh::{SubMesh, split_by_face_labels, split_by_vertex_labels};

/// `toothfuse info` arguments.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.ply, .stl, .obj, .vtp, .vtk) or a folder of tooth_<fdi> files.
    file: PathBuf,
}

fn describe(name: &str, m: &TriMesh) -> String {
    let r = m.topology_report();
    let closed = r.boundary_edges == 0 && r.non_manifold_edges == 0;
    let manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
    let problem = match m.validate(&Default::default()) {
        Ok(_) => String::new(),
        Err(e) => format!(" [first problem: {e}]"),
    };
    format!(
        "{name}: {} vertices, {} faces, {} boundary loop(s), {} component(s), closed={}, manifold={}{}{problem}",
        r.vertices,
        r.faces,
        r.boundary_loops,
        r.components,
        if closed { "yes" } else { "no" },
        if manifold { "yes" } else { "no" },
        if closed && manifold {
            format!(", volume={:.1} mm^3", m.signed_volume())
        } else {
            String::new()
        }
    )
}

/// Runs `toothfuse info`.
pub fn run(a: &InfoArgs) -> Result<()> {
    if a.file.is_dir() {
        let teeth = toothfuse::io::read_teeth(&a.file)
            .with_context(|| format!("reading {}", a.file.display()))?;
        println!("{}: folder of {} teeth", a.file.display(), teeth.len());
        for (fdi, m) in &teeth {
            println!("  {}", describe(&format!("tooth {fdi}"), m));
        }
        return Ok(());
    }
    let lm = toothfuse::io::read_mesh(&a.file)
        .with_context(|| format!("reading {}", a.file.display()))?;
    println!("{}", describe(&a.file.display().to_string(), &lm.mesh));
    let parts: Option<(&str, std::collections::BTreeMap<i32, SubMesh>)> =
        if let Some(l) = &lm.vertex_labels {
            Some(("per-vertex", split_by_vertex_labels(&lm.mesh, l)?))
        } else if let Some(l) = &lm.face_labels {
            Some(("per-face", split_by_face_labels(&lm.mesh, l)?))
        } else {
            None
        };
    match parts {
        None => println!("labels: none"),
        Some((kind, parts)) => {
            let names: Vec<String> = parts.keys().map(|k| k.to_string()).collect();
            println!("labels ({kind}): {}", names.join(" "));
            for (label, p) in &parts {
                let what = if *label == 0 {
                    "label 0 (gingiva)".to_string()
                } else {
                    format!("label {label}")
                };
                println!("  {}", describe(&what, &p.mesh));
            }
        }
    }
    Ok(())
}
