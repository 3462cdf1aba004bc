//! A per-jaw teeth mask split by the IOS where teeth touch, on toothfuse's own phantom: the
//! demo's `jaw_2` (`toothfuse demo --seed 3 --jaw upper --variant partial`, as
//! `cpp_tests/make_jaws.sh` writes it; 5 upper teeth, 11 and 21 touching at the midline). Its
//! CBCT teeth are voxelized at 0.3 mm on an oblique grid twice: with their FDI numbers (the
//! truth) and as DentalSegmentator's one upper-teeth class 3 (the input of the split). Per split
//! tooth, the share of its voxels that belong to another true tooth is measured against the
//! split's own confidence: a tooth split wrong by more than 5 % of its voxels must be refused or
//! reported (as contested, or as lying beyond the narrowest cut to a neighbour).

use glam::{DMat3, DVec3};
use std::collections::BTreeMap;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant, VoxelizeOptions, voxelize};
use toothfuse::volume::{LabelVolume, SplitOptions, split_teeth};

/// Demo jaw_2 of the C++ fixture.
fn jaw_2() -> Phantom {
    Phantom::generate(&PhantomOptions {
        seed: 3,
        jaw: Jaw::Upper,
        variant: Variant::PartialArch,
        ..Default::default()
    })
    .expect("phantom")
}

/// The C++ VTK test's oblique grid: 20° about x after 30° about z.
fn oblique() -> DMat3 {
    DMat3::from_rotation_x(20f64.to_radians()) * DMat3::from_rotation_z(30f64.to_radians())
}

/// What a split tooth holds that is not its own.
#[derive(Debug, Default)]
struct Wrong {
    /// Voxels of the split tooth.
    voxels: usize,
    /// Of them, voxels of another true tooth.
    wrong: usize,
    /// Its boundary voxels (a face neighbour not of the split tooth).
    surface: usize,
    /// Of them, voxels of another true tooth.
    wrong_surface: usize,
}

impl Wrong {
    fn share(&self) -> f64 {
        self.wrong as f64 / self.voxels.max(1) as f64
    }
    fn surface_share(&self) -> f64 {
        self.wrong_surface as f64 / self.surface.max(1) as f64
    }
}

/// Per split tooth, what of it belongs to another true tooth (`truth`: the same grid as the
/// volume the split was cropped from).
fn wrong_voxels(split: &LabelVolume, truth: &LabelVolume) -> BTreeMap<u16, Wrong> {
    // The split in the truth's grid.
    let inv = truth.voxel_to_world.inverse();
    let mut s = vec![0u16; truth.labels.len()];
    let [nx, ny, _] = split.dims;
    for (id, &l) in split.labels.iter().enumerate() {
        if l != 0 {
            let ijk = DVec3::new(
                (id % nx) as f64,
                ((id / nx) % ny) as f64,
                (id / (nx * ny)) as f64,
            );
            let t = inv.transform_point3(split.world(ijk)).round();
            s[truth.idx(t.x as usize, t.y as usize, t.z as usize)] = l;
        }
    }
    let [tx, ty, _] = truth.dims;
    let mut out: BTreeMap<u16, Wrong> = BTreeMap::new();
    for (id, &l) in s.iter().enumerate() {
        if l == 0 {
            continue;
        }
        // Tooth voxels never touch the volume's edge (the voxelizer pads it).
        let nb = [id - 1, id + 1, id - tx, id + tx, id - tx * ty, id + tx * ty];
        let on_surface = nb.iter().any(|&u| s[u] != l);
        let bad = truth.labels[id] != l;
        let e = out.entry(l).or_default();
        e.voxels += 1;
        e.wrong += bad as usize;
        e.surface += on_surface as usize;
        e.wrong_surface += (on_surface && bad) as usize;
    }
    out
}

/// The voxelized truth (FDI labels) and the one-class mask of jaw_2's CBCT teeth.
fn volumes(p: &Phantom) -> (LabelVolume, LabelVolume) {
    let opts = VoxelizeOptions {
        voxel_mm: 0.3,
        axes: oblique(),
        ..Default::default()
    };
    let truth = voxelize(&p.cbct, &opts).unwrap();
    let merged = voxelize(
        &p.cbct,
        &VoxelizeOptions {
            class: Some(3),
            ..opts
        },
    )
    .unwrap();
    (truth, merged)
}

/// Splits `merged` and prints, per tooth, what it holds of other teeth next to its reported
/// confidence.
fn split_and_measure(
    p: &Phantom,
    truth: &LabelVolume,
    merged: &LabelVolume,
    opts: &SplitOptions,
    what: &str,
) -> (toothfuse::volume::SplitVolume, BTreeMap<u16, Wrong>) {
    let split = split_teeth(merged, &p.ios_crowns(), opts).expect("split");
    let wrong = wrong_voxels(&split.volume, truth);
    let jaw = &split.jaws[0];
    for (fdi, t) in &jaw.teeth {
        let w = wrong
            .get(&(*fdi as u16))
            .map_or(Wrong::default(), |w| Wrong { ..*w });
        eprintln!(
            "{what}: tooth {fdi}: {} voxels, {} ({:.2}%) of another tooth, {:.1}% of its surface \
             voxels; reported {:.2}% contested, {:.1}% outside, {:.2}% beyond the narrowest cut \
             to a neighbour ({:.2}% handed over), {:.1}% of its boundary drawn by the split; \
             refused: {:?}",
            w.voxels,
            w.wrong,
            100.0 * w.share(),
            100.0 * w.surface_share(),
            100.0 * t.contested_share(),
            100.0 * t.outside_share(),
            100.0 * t.overrun_share(),
            100.0 * t.handed_over_share(),
            100.0 * t.interface_share(),
            jaw.refused.get(fdi)
        );
    }
    (split, wrong)
}

/// The split's options with the voxels beyond the narrowest cuts kept as the flood drew them.
fn as_drawn(axis_weight: f64) -> SplitOptions {
    SplitOptions {
        axis_weight,
        hand_over: false,
        ..Default::default()
    }
}

#[test]
fn where_teeth_touch_the_split_follows_each_root() {
    let p = jaw_2();
    let (truth, merged) = volumes(&p);
    assert_eq!(truth.dims, merged.dims);
    let axis = SplitOptions::default().axis_weight;
    let (split, wrong) = split_and_measure(&p, &truth, &merged, &as_drawn(axis), "as drawn");
    let jaw = &split.jaws[0];
    assert_eq!(jaw.teeth.len(), 5);
    assert!(split.refused().is_empty(), "{:?}", split.refused());
    // Measured: tooth 11 holds 0.18 % of 21's voxels (0.9 % of its surface voxels), the others
    // under 0.02 %.
    for (fdi, t) in &jaw.teeth {
        let w = &wrong[&(*fdi as u16)];
        assert!(w.share() < 0.005, "tooth {fdi}: {w:?}");
        assert!(w.surface_share() < 0.02, "tooth {fdi}: {w:?}");
        // The share beyond the narrowest cut to a neighbour is the share of another tooth's
        // voxels (measured: equal to 0.01 %).
        assert!(
            (t.overrun_share() - w.share()).abs() < 0.002,
            "tooth {fdi}: {t:?}"
        );
        // A split wrong by more than 5 % of a tooth's voxels would have to be reported.
        assert!(
            w.share() < 0.05 || t.contested_share() > 0.05 || t.overrun_share() > 0.05,
            "tooth {fdi}: {w:?}"
        );
    }
    // Without the long-axis prior (the split as it was): tooth 11 runs down 21's root from
    // their contact (measured: 1.8 % of its voxels, 8.4 % of its surface voxels are 21's)
    // while under 1 % of its voxels are contested.
    let (before_split, before) = split_and_measure(
        &p,
        &truth,
        &merged,
        &as_drawn(0.0),
        "as drawn, no axis prior",
    );
    assert!(before[&11].surface_share() > 0.05, "{:?}", before[&11]);
    assert!(before_split.jaws[0].teeth[&11].contested_share() < 0.02);
    // The narrowest cut between 11 and 21 sees it: 1.82 % of 11's voxels lie beyond it.
    let share = before_split.jaws[0].teeth[&11].overrun_share();
    assert!((share - before[&11].share()).abs() < 0.002, "{share}");
    // The boundary 11 and 21 share: the split drew 5.9 % of 11's boundary before, 1.1 % now
    // (the teeth touch only at their crowns' contact).
    assert!(
        jaw.teeth[&11].interface_share() < 0.5 * before_split.jaws[0].teeth[&11].interface_share()
    );
    // With the voxels beyond the narrowest cuts handed to the neighbours (the default), with
    // or without the long-axis prior: no tooth holds a voxel of another (measured), each handed
    // over exactly what lay beyond its cuts as drawn (11: 0.18 %, 1.82 % without the prior),
    // and nothing lies beyond a cut any more.
    for (drawn, axis_weight) in [(&split, axis), (&before_split, 0.0)] {
        let opts = SplitOptions {
            axis_weight,
            ..Default::default()
        };
        let (handed, wrong) = split_and_measure(&p, &truth, &merged, &opts, "handed over");
        assert!(handed.refused().is_empty(), "{:?}", handed.refused());
        for (fdi, t) in &handed.jaws[0].teeth {
            assert_eq!(wrong[&(*fdi as u16)].wrong, 0, "tooth {fdi}");
            assert_eq!(t.overrun_voxels, 0, "tooth {fdi}: {t:?}");
            let d = &drawn.jaws[0].teeth[fdi];
            assert_eq!(t.handed_over_voxels, d.overrun_voxels, "tooth {fdi}");
            assert_eq!(t.handed_over_to, d.overrun_into, "tooth {fdi}");
        }
        let t11 = &handed.jaws[0].teeth[&11];
        assert!((t11.handed_over_share() - drawn.jaws[0].teeth[&11].overrun_share()).abs() < 1e-12);
    }
}
