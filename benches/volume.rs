//! Surfacing CBCT teeth from a label volume: the STS 2024 mask (../shared/data/real, 0.25 mm,
//! 18 teeth of both jaws), one jaw and both, read once outside the timing. Target: a full jaw
//! well under a second. Skipped with a message when the real data is absent.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use toothfuse::io::read_label_volume;
use toothfuse::volume::{Frame, SurfaceOptions, VolumeScheme, surface_teeth};

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
    g.bench_function("read_sts_nifti_gz", |b| {
        b.iter(|| black_box(read_label_volume(&p, Frame::Lps).expect("read")))
    });
    g.finish();
}

criterion_group!(benches, bench_volume);
criterion_main!(benches);
