//! Fusing straight from a CBCT label volume, on a real-anatomy phantom made from the STS 2024
//! mask (../shared/data/real): the true teeth are the mask's lower-jaw teeth surfaced, the IOS is
//! simulated from them, and the CBCT is either the phantom's simulated CBCT meshes or the mask
//! itself placed in the phantom's random CBCT frame by composing its affine. Both paths are
//! measured against the truth (TRE over the whole true tooth, watertightness). Skipped with a
//! message when the real data is absent.

mod real_data;

use glam::DMat4;
use toothfuse::arch::Jaw;
use toothfuse::phantom::Phantom;
use toothfuse::pipeline::{self, PipelineOptions};
use toothfuse::volume::{SurfaceOptions, VolumeScheme, surface_teeth};

/// Mean TRE (mm) over the fused teeth and whether every fused tooth is watertight.
fn fuse_and_measure(p: &Phantom, what: &str) -> (f64, usize, bool) {
    let r = pipeline::fuse(&p.ios, &p.cbct, &PipelineOptions::default()).expect(what);
    let acc = pipeline::accuracy::fusion_accuracy(p, &r);
    let rep = r.report();
    let watertight = rep.teeth.iter().all(|t| t.watertight);
    let mean = acc.values().map(|a| a.tre_mm).sum::<f64>() / acc.len().max(1) as f64;
    for (fdi, a) in &acc {
        eprintln!("{what}: tooth {fdi} TRE {:.3} mm", a.tre_mm);
    }
    (mean, r.jaw.teeth.len(), watertight)
}

#[test]
fn per_tooth_volume_fuses_as_well_as_meshes() {
    let Some(vol) = real_data::sts_lower_teeth() else {
        return;
    };
    let p = real_data::phantom_on(&vol, Jaw::Lower, 5);
    assert_eq!(
        p.truth.teeth.keys().copied().collect::<Vec<_>>(),
        vec![31, 32, 33, 35, 36, 37, 41, 42, 43, 44]
    );
    // The mask in the phantom's CBCT frame: its affine composed with world -> CBCT.
    let w2c = p.truth.world_to_cbct;
    let placed = {
        let mut v = vol.clone();
        let m = DMat4::from_mat3_translation(w2c.rot, w2c.trans);
        v.voxel_to_world = m * v.voxel_to_world;
        v
    };
    let from_volume = surface_teeth(&placed, VolumeScheme::Fdi, &SurfaceOptions::default())
        .unwrap()
        .teeth;
    let mut pv = p.clone();
    pv.cbct = from_volume.into_iter().map(|(f, t)| (f, t.mesh)).collect();
    let (tre_mesh, n_mesh, wt_mesh) = fuse_and_measure(&p, "from meshes");
    let (tre_vol, n_vol, wt_vol) = fuse_and_measure(&pv, "from the volume");
    eprintln!(
        "mean TRE: from meshes {tre_mesh:.3} mm ({n_mesh} teeth), from the per-tooth volume \
         {tre_vol:.3} mm ({n_vol} teeth)"
    );
    assert!(wt_mesh && wt_vol);
    assert_eq!(n_vol, 10, "every tooth of the volume fused");
    assert!(n_vol >= n_mesh);
    // As good as from meshes (the volume path's CBCT is the true surface, the mesh path's is
    // the simulated blurry CBCT).
    assert!(tre_vol <= tre_mesh * 1.1 + 0.02, "{tre_vol} vs {tre_mesh}");
    assert!(tre_vol < 0.3, "{tre_vol}");
}
