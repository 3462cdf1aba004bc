//! `toothfuse info`: facts about a mesh file, whole and per label.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::io::{Detected, LabelScheme, TeethOptions, detect_scheme};
use toothfuse::mesh::{SubMesh, split_by_face_labels, split_by_vertex_labels};

/// `toothfuse info` arguments.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.ply, .stl, .obj, .vtp, .vtk) or a folder of tooth_<n> files.
    file: PathBuf,
    /// Name of the label array (point or cell data; PLY vertex or face property). Default:
    /// the first known name (Label, labels, UniversalID, PredictedID, FDI, ...).
    #[arg(long, value_name = "NAME")]
    label_array: Option<String>,
    /// Tooth numbering of the labels; auto detects it where unambiguous.
    #[arg(long, default_value = "auto", value_parser = ["auto", "fdi", "universal", "meshlabeler"])]
    labels: String,
}

/// `label→FDI` pairs of the non-gingiva labels, or why they do not map.
fn fdi_map(d: &Detected, labels: impl Iterator<Item = i32>) -> String {
    let mut out = Vec::new();
    for l in labels {
        if d.scheme.is_gingiva(l) {
            out.push(format!("{l}=gingiva"));
            continue;
        }
        match d.scheme.to_fdi(l) {
            Ok(f) => out.push(format!("{l}->{f}")),
            Err(e) => return format!("does not map: {e}"),
        }
    }
    out.join(" ")
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
    let given = LabelScheme::from_name(&a.labels);
    if a.file.is_dir() {
        let opts = TeethOptions {
            scheme: given,
            label_array: None,
        };
        let t = toothfuse::io::read_teeth_opts(&a.file, &opts)
            .with_context(|| format!("reading {}", a.file.display()))?;
        println!("{}: folder of {} teeth", a.file.display(), t.teeth.len());
        println!(
            "numbering: {} ({})",
            t.scheme.scheme.name(),
            t.scheme.reason
        );
        for (fdi, m) in &t.teeth {
            println!("  {}", describe(&format!("tooth {fdi}"), m));
        }
        return Ok(());
    }
    let f = toothfuse::io::read_mesh_with(&a.file, a.label_array.as_deref())
        .with_context(|| format!("reading {}", a.file.display()))?;
    let lm = &f.mesh;
    println!("{}", describe(&a.file.display().to_string(), &lm.mesh));
    match (
        &f.label_array,
        lm.face_labels.as_ref().or(lm.vertex_labels.as_ref()),
    ) {
        (Some(name), Some(values)) => {
            let on = f
                .arrays
                .iter()
                .filter(|x| &x.name == name)
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(" and ");
            println!("label array: {on}");
            let shown = a.file.display().to_string();
            let d = match given {
                Some(s) => Ok(Detected {
                    scheme: s,
                    reason: "given by --labels".into(),
                }),
                None => detect_scheme(&shown, Some(name), f.teeth3ds_json, values),
            };
            let mut distinct = values.clone();
            distinct.sort_unstable();
            distinct.dedup();
            match d {
                Ok(d) => {
                    println!("numbering: {} ({})", d.scheme.name(), d.reason);
                    println!("FDI: {}", fdi_map(&d, distinct.into_iter()));
                }
                Err(e) => println!("numbering: not detected: {e}"),
            }
        }
        _ => println!(
            "label array: none found; one-component arrays in the file: {} (name one with \
             --label-array)",
            f.arrays_list()
        ),
    }
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
