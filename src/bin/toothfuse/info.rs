//! `toothfuse info`: facts about a mesh file, whole and per label.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::io::{Detected, LabelScheme, TeethOptions, detect_scheme};
use toothfuse::mesh::{SubMesh, split_by_face_labels, split_by_vertex_labels};
use toothfuse::volume::{Frame, VolumeScheme};

/// `toothfuse info` arguments.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.ply, .stl, .obj, .vtp, .vtk), a folder of tooth_<n> files, or a label
    /// volume (.nii, .nii.gz, .nrrd, .seg.nrrd).
    file: PathBuf,
    /// Name of the label array (point or cell data; PLY vertex or face property). Default:
    /// the first known name (Label, labels, UniversalID, PredictedID, FDI, ...).
    #[arg(long, value_name = "NAME")]
    label_array: Option<String>,
    /// Tooth numbering of the labels; auto detects it where unambiguous.
    #[arg(long, default_value = "auto", value_parser = ["auto", "fdi", "universal", "meshlabeler"])]
    labels: String,
    /// World frame to print a label volume's voxel-to-world matrix in.
    #[arg(long, default_value = "lps", value_parser = ["lps", "ras"])]
    frame: String,
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

/// Facts about a label volume: format, grid, orientation, labels.
fn volume_info(a: &InfoArgs) -> Result<()> {
    let frame = Frame::from_name(&a.frame).unwrap_or_default();
    let vf = toothfuse::io::read_label_volume(&a.file, frame)
        .with_context(|| format!("reading {}", a.file.display()))?;
    let (h, v) = (&vf.header, &vf.volume);
    let s = v.spacing();
    println!(
        "{}: {} label volume, {}x{}x{} {}, voxel {:.4} x {:.4} x {:.4} mm",
        a.file.display(),
        h.format,
        h.full_dims[0],
        h.full_dims[1],
        h.full_dims[2],
        h.element,
        s[0],
        s[1],
        s[2]
    );
    println!(
        "orientation: voxel axes {} (from the {}), {}; world frame {}",
        v.axis_codes(),
        h.orientation_source,
        if v.is_oblique() {
            "oblique"
        } else {
            "axis-aligned"
        },
        frame.name()
    );
    let m = h.full_voxel_to_world;
    for r in 0..3 {
        let row = m.row(r);
        println!(
            "  [{:10.4} {:10.4} {:10.4} {:10.4}]",
            row.x, row.y, row.z, row.w
        );
    }
    let voxel = s[0] * s[1] * s[2];
    let boxes = v.label_boxes();
    let counts = v.label_counts();
    let seg: std::collections::BTreeMap<u16, &str> =
        h.segments.iter().map(|(l, n)| (*l, n.as_str())).collect();
    println!("labels: {}", counts.len());
    for (l, c) in &counts {
        let (lo, hi) = boxes[l];
        let ext: Vec<String> = (0..3)
            .map(|k| format!("{:.1}", (hi[k] - lo[k] + 1) as f64 * s[k]))
            .collect();
        let fdi = VolumeScheme::Fdi
            .tooth_fdi(*l)
            .ok()
            .flatten()
            .map(|f| format!(", FDI {f}"))
            .unwrap_or_default();
        let name = seg.get(l).map(|n| format!(" \"{n}\"")).unwrap_or_default();
        println!(
            "  label {l}{name}: {c} voxels, {:.1} mm^3, extent {} mm{fdi}",
            *c as f64 * voxel,
            ext.join(" x ")
        );
    }
    let keys: Vec<u16> = counts.keys().copied().collect();
    if toothfuse::volume::numbering::looks_like_dentalsegmentator(&keys) {
        println!(
            "these look like DentalSegmentator classes: 1 maxilla, 2 mandible, 3 upper teeth, 4 \
             lower teeth, 5 mandibular canal (no tooth numbers)"
        );
    }
    Ok(())
}

fn describe(name: &str, m: &TriMesh) -> String {
    // A mesh that validates comes with its topology report (built once); only a mesh with a
    // problem needs the report made apart.
    let (r, problem) = match m.validate(&Default::default()) {
        Ok(r) => (r, String::new()),
        Err(e) => (m.topology_report(), format!(" [first problem: {e}]")),
    };
    let closed = r.boundary_edges == 0 && r.non_manifold_edges == 0;
    let manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
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
    if toothfuse::io::is_volume_path(&a.file) {
        return volume_info(a);
    }
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
