//! Surfacing CBCT teeth from a label volume: the STS 2024 mask (../shared/data/real, 0.25 mm,
//! 18 teeth of both jaws), one jaw and both, read once outside the timing. Target: a full jaw
//! well under a second. And splitting the mask's lower teeth merged into one per-jaw class
//! (DentalSegmentator style) with the IOS crowns of a phantom built on them (built outside the
//! timing). Skipped with a message when the real data is absent.

#[path = "../tests/real_data/mod.rs"]
mod real_data;

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use toothfuse::io::read_label_volume;
use toothfuse::volume::{
    Frame, LabelVolume, SplitOptions, SurfaceOptions, VolumeScheme, split_teeth, surface_teeth,
};

/// The lower teeth merged into class 4 and the IOS crowns of a phantom built on them.
fn per_jaw_lower(
    both: &LabelVolume,
) -> (
    LabelVolume,
    std::collections::BTreeMap<u8, toothfuse::TriMesh>,
) {
    let lower = real_data::lower_teeth(both);
    let p = real_data::phantom_on(&lower, toothfuse::arch::Jaw::Lower, 5);
    (
        lower.relabeled(|l| if l != 0 { 4 } else { 0 }),
        p.ios_crowns(),
    )
}

fn bench_volume(c: &mut Criterion) {
    let Some(dir) = toothfuse::io::real_data_dir() else {
        eprintln!("SKIPPED: real data folder not found (set TOOTHFUSE_REAL_DATA)");
        return;
    };
    let p = dir.join("cbct_toothseg_sts2024/Validation_0001_Mask.nii.gz");
    let Ok(vf) = read_label_volume(&p, Frame::Lps) else {
        eprintln!("SKIPPED: {} not readable", p.display());
        return;
    };
    let both = vf.volume;
    let upper = both.relabeled(|l| if (11..=28).contains(&l) { l } else { 0 });
    let opts = SurfaceOptions::default();
    let mut g = c.benchmark_group("volume");
    g.sample_size(10);
    g.bench_function("surface_sts_upper_jaw", |b| {
        b.iter(|| black_box(surface_teeth(&upper, VolumeScheme::Fdi, &opts).expect("teeth")))
    });
    g.bench_function("surface_sts_both_jaws", |b| {
        b.iter(|| black_box(surface_teeth(&both, VolumeScheme::Fdi, &opts).expect("teeth")))
    });
    let (merged, crowns) = per_jaw_lower(&both);
    let split = SplitOptions::default();
    g.bench_function("split_sts_lower_jaw_by_ios", |b| {
        b.iter(|| black_box(split_teeth(&merged, &crowns, &split).expect("split")))
    });
    g.bench_function("read_sts_nifti_gz", |b| {
        b.iter(|| black_box(read_label_volume(&p, Frame::Lps).expect("read")))
    });
    g.finish();
}

criterion_group!(benches, bench_volume);
criterion_main!(benches);
