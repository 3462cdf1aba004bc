//! The output contract on real crowns: the 14 crowns of a real intraoral scan (Mesh Labeler
//! Example_01, cut out by a segmentation tool's per-face labels: broken patches with bow-ties,
//! islands, slivers and ragged margins), each fused onto a phantom CBCT tooth of the same FDI
//! number placed under it (no matched real CBCT exists: the phantom tooth is moved and scaled so
//! that its crown's margin frame meets the real crown's, then moved by a rigid fit of its crown
//! to the real one). The root is synthetic, the crown and its margin are not. Every fused tooth must be closed, manifold, one component, outward, with
//! no intersecting face pair other than two kept input crown faces (exact test), every kept IOS
//! vertex bitwise where it was, and every input crown vertex kept, trimmed or dropped.
//! Skips when the real data folder is absent.

use glam::{DMat3, DVec3};
use std::collections::BTreeMap;
use toothfuse::arch::Jaw;
use toothfuse::cut::ToothFrame;
use toothfuse::fuse::{FuseOptions, Preset, fuse_tooth, ios_crowns};
use toothfuse::io::{read_mesh, real_data_dir};
use toothfuse::mesh::{
    RepairOptions, TriMesh, boundary_loops, repair_open_surface, split_by_face_labels,
};
use toothfuse::mesh_check::self_intersections;
use toothfuse::phantom::{Phantom, PhantomOptions};
use toothfuse::{Rigid, geom};

/// Mesh Labeler's ordinal labels of an upper scan: 1..8 = FDI 18..11, 9..16 = FDI 21..28.
fn ordinal_to_fdi(l: i32) -> Option<u8> {
    match l {
        1..=8 => Some(19 - l as u8),
        9..=16 => Some(12 + l as u8),
        _ => None,
    }
}

/// A crown's margin frame (from its repaired disk's boundary) and margin radius.
fn margin_frame(crown: &TriMesh) -> (ToothFrame, f64) {
    let (disk, _, _) = repair_open_surface(crown, &RepairOptions::default());
    let loops = boundary_loops(&disk);
    let pts: Vec<DVec3> = loops[0]
        .iter()
        .map(|&v| disk.positions[v as usize])
        .collect();
    let c = geom::centroid(&disk.positions).expect("crown");
    let f = ToothFrame::from_margin(&pts, c).expect("frame");
    let r = pts.iter().map(|p| (*p - f.center).length()).sum::<f64>() / pts.len() as f64;
    (f, r)
}

/// An orthonormal basis (axis, lingual, axis x lingual) of a crown in its arch: the lingual
/// direction points from the crown to the arch's centre, across the axis.
fn basis(f: &ToothFrame, arch_centre: DVec3) -> DMat3 {
    let to = arch_centre - f.center;
    let l = (to - f.axis * to.dot(f.axis)).normalize();
    DMat3::from_cols(f.axis, l, f.axis.cross(l))
}

/// Rigid point-to-point ICP of `src` onto `dst` (nearest points by a full scan, every sixth
/// source point; 20 iterations): the transform taking `src` onto `dst`.
fn icp(src: &[DVec3], dst: &[DVec3]) -> Rigid {
    let mut t = Rigid::IDENTITY;
    for _ in 0..20 {
        let moved: Vec<DVec3> = src.iter().step_by(6).map(|&p| t.apply(p)).collect();
        let near: Vec<DVec3> = moved
            .iter()
            .map(|&p| {
                *dst.iter()
                    .min_by(|a, b| {
                        (**a - p)
                            .length_squared()
                            .total_cmp(&(**b - p).length_squared())
                    })
                    .expect("points")
            })
            .collect();
        let step = toothfuse::register::centroid::kabsch(&moved, &near, None).expect("kabsch");
        t = step.compose(&t);
    }
    t
}

#[test]
fn real_scan_crowns_fuse_onto_phantom_roots_within_the_contract() {
    let Some(dir) = real_data_dir() else {
        println!("SKIPPED: ../shared/data/real not found (set TOOTHFUSE_REAL_DATA)");
        return;
    };
    let lm = read_mesh(dir.join("ios_mesh_labeler/Example_01.vtp")).expect("Example_01.vtp");
    let labels = lm.face_labels.clone().expect("per-face labels");
    let real: BTreeMap<u8, TriMesh> = split_by_face_labels(&lm.mesh, &labels)
        .expect("split")
        .into_values()
        .filter_map(|p| ordinal_to_fdi(p.label).map(|f| (f, p.mesh)))
        .collect();
    assert_eq!(real.len(), 14);
    let p = Phantom::generate(&PhantomOptions {
        seed: 1,
        jaw: Jaw::Upper,
        ..Default::default()
    })
    .expect("phantom");
    let tr = toothfuse::eval::true_transforms(&p);
    let phantom_crowns = ios_crowns(&p.ios).expect("phantom crowns");
    let frames = |crowns: &BTreeMap<u8, TriMesh>, to_out: &dyn Fn(u8) -> Rigid| {
        let f: BTreeMap<u8, (ToothFrame, f64)> = crowns
            .iter()
            .map(|(&fdi, c)| (fdi, margin_frame(&c.transformed(&to_out(fdi)))))
            .collect();
        let centres: Vec<DVec3> = f.values().map(|(fr, _)| fr.center).collect();
        let centre = geom::centroid(&centres).expect("arch");
        (f, centre)
    };
    let (real_f, real_c) = frames(&real, &|_| Rigid::IDENTITY);
    let (ph_f, ph_c) = frames(&phantom_crowns, &|fdi| tr[&fdi].ios_to_output);
    let opts = FuseOptions::preset(Preset::Default);
    let mut fused = 0;
    let mut failed = Vec::new();
    let mut crossed = Vec::new();
    for (&fdi, crown) in &real {
        let (Some((fr, rr)), Some((fp, rp)), Some(cbct)) =
            (real_f.get(&fdi), ph_f.get(&fdi), p.cbct.get(&fdi))
        else {
            continue;
        };
        // The phantom tooth in the output frame, then moved and scaled so that its crown's
        // margin frame meets the real crown's.
        let (br, bp) = (basis(fr, real_c), basis(fp, ph_c));
        let (rot, s) = (br * bp.transpose(), rr / rp);
        let place = |v: DVec3| fr.center + rot * ((v - fp.center) * s);
        // Then the phantom crown fitted to the real one (rigid ICP, nearest points), so that
        // the CBCT tooth sits where its crown matches best.
        let ph_crown: Vec<DVec3> = phantom_crowns[&fdi]
            .positions
            .iter()
            .map(|&v| place(tr[&fdi].ios_to_output.apply(v)))
            .collect();
        let fit = icp(&ph_crown, &crown.positions);
        let to_out = tr[&fdi].cbct_to_output;
        let placed = TriMesh::new(
            cbct.positions
                .iter()
                .map(|&v| fit.apply(place(to_out.apply(v))))
                .collect(),
            cbct.triangles.clone(),
        );
        let t = match fuse_tooth(
            fdi,
            crown,
            &placed,
            &Rigid::IDENTITY,
            &Rigid::IDENTITY,
            &opts,
        ) {
            Ok(t) => t,
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(&fdi.to_string()),
                    "tooth {fdi}: error names no tooth: {msg}"
                );
                println!("tooth {fdi}: not fused: {msg}");
                failed.push(fdi);
                continue;
            }
        };
        fused += 1;
        if fdi == 11 {
            assert!(
                t.warnings
                    .iter()
                    .any(|w| w.contains("cut about the long axis")),
                "real crown 11: {:?}",
                t.warnings
            );
        }
        let q = &t.quality;
        let what = format!("real crown {fdi}");
        assert!(q.closed && q.manifold && q.components == 1, "{what}: {q:?}");
        assert!(q.volume > 0.0, "{what}: volume {}", q.volume);
        let added: Vec<_> = self_intersections(&t.mesh)
            .into_iter()
            .filter(|&(a, b)| {
                (a as usize) >= t.band_faces.start || (b as usize) >= t.band_faces.start
            })
            .collect();
        // The report names what is left: its count is the pairs found, with a warning.
        assert_eq!(q.band_crossings_left, added.len(), "{what}");
        if !added.is_empty() {
            assert!(
                t.warnings
                    .iter()
                    .any(|w| w.contains("intersecting face pairs with a band face")),
                "{what}: {} pairs left without a warning: {:?}",
                added.len(),
                t.warnings
            );
            println!("{what}: {} crossing pairs added", added.len());
            crossed.push((fdi, added.len()));
        }
        for (v, &src) in t.ios_vertex.iter().enumerate() {
            if src != u32::MAX {
                assert_eq!(
                    t.mesh.positions[v], crown.positions[src as usize],
                    "{what}: vertex {v}"
                );
            }
        }
        let kept = t.ios_vertex.iter().filter(|&&s| s != u32::MAX).count();
        assert_eq!(kept, q.crown_vertices, "{what}");
        let used = {
            let mut u = vec![false; crown.positions.len()];
            crown
                .triangles
                .iter()
                .flatten()
                .for_each(|&v| u[v as usize] = true);
            u.iter().filter(|&&x| x).count()
        };
        assert!(
            kept + q.ios_vertices_trimmed + q.ios_vertices_dropped >= used,
            "{what}: kept {kept} + trimmed {} + dropped {} against {used} crown vertices in faces",
            q.ios_vertices_trimmed,
            q.ios_vertices_dropped
        );
        println!(
            "{what}: fused; {} of {} IOS vertices trimmed (up to {:.2} mm), {} dropped, warnings {:?}",
            q.ios_vertices_trimmed, used, q.ios_trim_reach_mm, q.ios_vertices_dropped, t.warnings
        );
    }
    println!("{fused} of 14 real crowns fused; not fused: {failed:?}; crossed: {crossed:?}");
    // The central incisor 11, whose labelled margin is a saddle dropping ~6 mm below its
    // interproximal horns, tilts the margin's plane 45° from the CBCT tooth's long axis and is
    // cut about that axis (it was refused while that retry needed a tilt over 45°).
    assert!(failed.is_empty(), "real crowns not fused: {failed:?}");
    assert!(
        crossed.is_empty(),
        "crossing pairs added on real crowns: {crossed:?}"
    );
}
