//! `toothfuse info`: facts about a mesh file, whole and per label.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::mesh::{SubMesh, split_by_face_labels, split_by_vertex_labels};
use toothfuse::volume::{Frame, VolumeScheme};

/// `toothfuse info` arguments.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.ply, .stl, .obj, .vtp, .vtk), a folder of tooth_<fdi> files, or a label
    /// volume (.nii, .nii.gz, .nrrd, .seg.nrrd).
    file: PathBuf,
    /// World frame to print a label volume's voxel-to-world matrix in.
    #[arg(long, default_value = "lps", value_parser = ["lps", "ras"])]
    frame: String,
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
    if toothfuse::io::is_volume_path(&a.file) {
        return volume_info(a);
    }
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
