//! Generation time of the synthetic jaw (a full arch, both jaws; and the rough export of the
//! upper one). Target: under 5 s each in release mode on a 2-core machine, single-threaded; a
//! rough jaw no dearer than a clean one.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant};

fn bench_phantom(c: &mut Criterion) {
    let mut g = c.benchmark_group("phantom");
    g.sample_size(10);
    for jaw in [Jaw::Upper, Jaw::Lower] {
        let opts = PhantomOptions {
            seed: 1,
            jaw,
            variant: Variant::Full,
            ..Default::default()
        };
        g.bench_function(format!("generate_full_{jaw:?}").to_lowercase(), |b| {
            b.iter(|| black_box(Phantom::generate_uncached(black_box(&opts)).expect("phantom")))
        });
    }
    let mut rough = PhantomOptions {
        seed: 1,
        jaw: Jaw::Upper,
        variant: Variant::Full,
        ..Default::default()
    };
    rough.realism.ios.rough = IosExport::Rough.roughness();
    g.bench_function("generate_full_upper_rough", |b| {
        b.iter(|| black_box(Phantom::generate_uncached(black_box(&rough)).expect("phantom")))
    });
    g.finish();
}

criterion_group!(benches, bench_phantom);
criterion_main!(benches);
