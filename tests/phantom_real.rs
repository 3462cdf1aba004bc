//! The phantom on real tooth shapes: Open-Full-Jaw patient 26 mandible (closed CBCT-segmented
//! teeth, UNN numbering) as the true anatomy. Skips when the real data folder is absent.

mod phantom_support;

use phantom_support::*;
use std::collections::BTreeMap;
use std::path::PathBuf;
use toothfuse::arch::Jaw;
use toothfuse::mesh::TriMesh;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};

fn real_dir() -> PathBuf {
    std::env::var_os("TOOTHFUSE_REAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"))
        })
}

/// UNN (Universal) mandibular numbers 17–32 → FDI 38…31, 41…48.
fn unn_to_fdi_lower(n: u32) -> Option<u8> {
    match n {
        17..=24 => Some(38 - (n - 17) as u8),
        25..=32 => Some(41 + (n - 25) as u8),
        _ => None,
    }
}

fn read_stl(path: &std::path::Path) -> TriMesh {
    let mut f = std::fs::File::open(path).expect("open STL");
    let m = stl_io::read_stl(&mut f).expect("read STL");
    TriMesh::new(
        m.vertices
            .iter()
            .map(|v| glam::DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
            .collect(),
        m.faces
            .iter()
            .map(|t| t.vertices.map(|i| i as u32))
            .collect(),
    )
}

fn mandible() -> Option<BTreeMap<u8, TriMesh>> {
    let dir = real_dir().join("cbct_teeth_openfulljaw_p26/mandible");
    if !dir.is_dir() {
        eprintln!("SKIP: real data folder {} is absent", dir.display());
        return None;
    }
    let mut teeth = BTreeMap::new();
    // Second molars to second molars (the 14 teeth of the synthetic jaw), to keep it quick.
    for n in 18..=31u32 {
        let path = dir.join(format!("tooth_{n}.stl"));
        if let (true, Some(fdi)) = (path.is_file(), unn_to_fdi_lower(n)) {
            teeth.insert(fdi, read_stl(&path));
        }
    }
    Some(teeth)
}

#[test]
fn real_mandible_as_anatomy() {
    let Some(anatomy) = mandible() else { return };
    assert_eq!(anatomy.len(), 14);
    let p = Phantom::generate(&PhantomOptions {
        seed: 11,
        jaw: Jaw::Lower,
        variant: Variant::Full,
        anatomy: Some(anatomy.clone()),
        ..Default::default()
    })
    .expect("phantom from real anatomy");
    assert_eq!(
        p.truth.teeth.keys().copied().collect::<Vec<_>>(),
        anatomy.keys().copied().collect::<Vec<_>>()
    );
    let back_cbct = p.truth.world_to_cbct.inverse();
    let crowns = p.ios_crowns();
    assert_eq!(crowns.len(), 14);
    let mut all = Vec::new();
    for (fdi, t) in &p.truth.teeth {
        // The truth keeps the real tooth where it was.
        assert_eq!(
            t.surface.positions.len(),
            anatomy[fdi].positions.len(),
            "tooth {fdi}"
        );
        assert!(
            t.surface.positions == anatomy[fdi].positions,
            "tooth {fdi}: positions"
        );
        assert!(
            t.surface.triangles == anatomy[fdi].triangles,
            "tooth {fdi}: triangles"
        );
        let sd = SurfaceDistance::new(&t.surface);
        // The long axis points from the root to the crown: the crown tip is along +axis.
        let c = toothfuse::geom::centroid(&t.surface.positions).unwrap();
        let reach = t
            .surface
            .positions
            .iter()
            .map(|q| (*q - c).dot(t.axis))
            .fold(f64::NEG_INFINITY, f64::max);
        let depth = t
            .surface
            .positions
            .iter()
            .map(|q| (*q - c).dot(t.axis))
            .fold(f64::INFINITY, f64::min);
        assert!(
            reach < -depth,
            "tooth {fdi}: the crown is the shorter half of the tooth"
        );
        // Margin points lie on the real surface.
        for m in &t.margin {
            assert!(
                sd.distance(*m) < 0.15,
                "tooth {fdi}: margin point off the surface"
            );
        }
        let cb = &p.cbct[fdi];
        assert_closed_tooth(cb, &format!("real cbct {fdi}"));
        let d: Vec<f64> = cb
            .positions
            .iter()
            .map(|&q| sd.distance(back_cbct.apply(q)))
            .collect();
        let (rms, _, _) = stats(&d);
        assert!((0.05..=0.45).contains(&rms), "real cbct {fdi}: RMS {rms}");
        all.extend(d);
        let crown = &crowns[fdi];
        assert_disk(crown, &format!("real ios crown {fdi}"));
        let back = p.truth.world_to_ios.compose(&t.ios_drift).inverse();
        let mut di: Vec<f64> = crown
            .positions
            .iter()
            .map(|&q| sd.distance(back.apply(q)))
            .collect();
        di.sort_by(|a, b| a.total_cmp(b));
        let q90 = di[di.len() * 9 / 10];
        assert!(q90 < 0.08, "real ios crown {fdi}: 90% quantile {q90}");
    }
    let (rms, mean, max) = stats(&all);
    eprintln!(
        "real mandible CBCT vs truth: RMS {rms:.3} mean {mean:.3} max {max:.3}; IOS {} vertices",
        p.ios.mesh.positions.len()
    );
}
