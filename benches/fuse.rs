//! Crown removal + stitching of a full synthetic jaw (14 teeth) with the true transforms.

use criterion::{Criterion, criterion_group, criterion_main};
use std::collections::BTreeMap;
use std::hint::black_box;
use toothfuse::fuse::{FuseOptions, Preset, ToothTransforms, fuse_jaw};
use toothfuse::phantom::{Phantom, PhantomOptions};

fn bench(c: &mut Criterion) {
    let p = Phantom::generate(&PhantomOptions::default()).expect("phantom");
    let transforms: BTreeMap<u8, ToothTransforms> = toothfuse::eval::true_transforms(&p);
    let mut g = c.benchmark_group("fuse");
    g.sample_size(10);
    for preset in [Preset::Default, Preset::Paper] {
        let opts = FuseOptions::preset(preset);
        g.bench_function(format!("cut_stitch_full_jaw_{}", preset.name()), |b| {
            b.iter(|| black_box(fuse_jaw(&p.ios, &p.cbct, &transforms, &opts).expect("fuse")))
        });
    }
    // The whole one-call fuse a host runs: register, cut and stitch every tooth.
    let crowns = toothfuse::fuse::ios_crowns(&p.ios).expect("crowns");
    let po = toothfuse::pipeline::PipelineOptions::default();
    g.bench_function("register_cut_stitch_full_jaw_default", |b| {
        b.iter(|| black_box(toothfuse::pipeline::fuse_crowns(&crowns, &p.cbct, &po).expect("fuse")))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
