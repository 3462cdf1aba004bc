//! Generation time of the synthetic jaw (a full arch, both jaws). Target: under 5 s each in
//! release mode on a 2-core machine, single-threaded.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};

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
            b.iter(|| black_box(Phantom::generate(black_box(&opts)).expect("phantom")))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_phantom);
criterion_main!(benches);
