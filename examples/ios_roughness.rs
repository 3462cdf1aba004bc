//! What the IOS crowns of each phantom export hold, and the same for labelled IOS files (the
//! README's table of rough exports):
//! `cargo run --release --example ios_roughness -- [seed] [upper|lower] [variant] [export...]`
//! (default `1 upper full` and every export), or `... -- --files A.ply B.ply` for IOS files.
//! Per jaw: IOS vertices, crowns, mean crown edge, crown faces with a corner under 5°, crown
//! face pairs that cross (exact test, within each crown), crowns with more than one component
//! or boundary loop, and the generation time.

use std::time::Instant;
use toothfuse::arch::Jaw;
use toothfuse::mesh::{LabeledMesh, TriMesh, split_by_vertex_labels};
use toothfuse::mesh_check::self_intersections;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant};

fn min_angle_deg(m: &TriMesh, t: [u32; 3]) -> f64 {
    let p = t.map(|v| m.positions[v as usize]);
    (0..3)
        .map(|k| {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            a.angle_between(b).to_degrees()
        })
        .fold(180.0, f64::min)
}

fn survey(name: &str, ios: &LabeledMesh, seconds: Option<f64>) {
    let labels = ios.vertex_labels.as_ref().expect("vertex labels");
    let parts = split_by_vertex_labels(&ios.mesh, labels).expect("split");
    let (mut crowns, mut verts, mut faces, mut slivers, mut crossings) = (0, 0, 0, 0, 0);
    let (mut edge_sum, mut edges, mut extra_loops, mut extra_comps) = (0.0, 0usize, 0, 0);
    let mut max_crossings = 0;
    for (l, s) in parts.iter().filter(|(l, _)| **l > 0) {
        let _ = l;
        let m = &s.mesh;
        crowns += 1;
        verts += m.positions.len();
        faces += m.triangles.len();
        for t in &m.triangles {
            if min_angle_deg(m, *t) < 5.0 {
                slivers += 1;
            }
            for k in 0..3 {
                edge_sum +=
                    (m.positions[t[k] as usize] - m.positions[t[(k + 1) % 3] as usize]).length();
                edges += 1;
            }
        }
        let c = self_intersections(m).len();
        crossings += c;
        max_crossings = max_crossings.max(c);
        let r = m.topology_report();
        extra_loops += usize::from(r.boundary_loops > 1);
        extra_comps += usize::from(r.components > 1);
    }
    println!(
        "| {name} | {} | {crowns} | {verts} | {:.3} | {:.1} % | {crossings} (max {max_crossings}) | {extra_comps} / {extra_loops} | {} |",
        ios.mesh.positions.len(),
        edge_sum / edges.max(1) as f64,
        100.0 * slivers as f64 / faces.max(1) as f64,
        seconds.map_or("-".into(), |s| format!("{s:.2} s")),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    println!(
        "| jaw | IOS vertices | crowns | crown vertices | mean crown edge (mm) | crown faces < 5° | crossing crown face pairs | crowns with >1 component / >1 boundary loop | generation |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    if args.first().map(String::as_str) == Some("--files") {
        for f in &args[1..] {
            let ios = toothfuse::io::read_mesh(f).expect("IOS file");
            survey(f, &ios, None);
        }
        return;
    }
    let seed: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(1);
    let jaw = if args.get(1).map(String::as_str) == Some("lower") {
        Jaw::Lower
    } else {
        Jaw::Upper
    };
    let variant = args
        .get(2)
        .and_then(|s| Variant::from_name(s))
        .unwrap_or(Variant::Full);
    let exports: Vec<IosExport> = if args.len() > 3 {
        args[3..]
            .iter()
            .map(|s| IosExport::from_name(s).expect("export name"))
            .collect()
    } else {
        IosExport::ALL.to_vec()
    };
    for e in exports {
        let mut opts = PhantomOptions {
            seed,
            jaw,
            variant,
            ..Default::default()
        };
        opts.realism.ios.rough = e.roughness();
        let t = Instant::now();
        let p = Phantom::generate(&opts).expect("phantom");
        let s = t.elapsed().as_secs_f64();
        let name = format!("seed {seed} {jaw:?} {} {}", variant.name(), e.name());
        survey(&name, &p.ios, Some(s));
    }
}
