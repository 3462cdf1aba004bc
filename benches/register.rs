//! Full-jaw registration (14 teeth, realistic phantom sizes): default and paper presets; and a
//! short arch whose first jaw-wide fit lands in a wrong minimum, so that the coarse stage's
//! restarts run (a 4-tooth lower posterior segment, rough export).

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use toothfuse::arch::Jaw;
use toothfuse::eval::phantom_inputs;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant};
use toothfuse::register::{RegisterOptions, register};

fn bench(c: &mut Criterion) {
    let p = Phantom::generate(&PhantomOptions::default()).expect("phantom");
    let (ios, cbct) = phantom_inputs(&p).expect("inputs");
    let points: usize = ios.values().map(|m| m.positions.len()).sum();
    eprintln!(
        "{} teeth, {} IOS vertices, {} CBCT vertices",
        ios.len(),
        points,
        cbct.values().map(|m| m.positions.len()).sum::<usize>()
    );
    let mut g = c.benchmark_group("register");
    g.sample_size(10);
    let def = RegisterOptions::default();
    g.bench_function("default_14_teeth", |b| {
        b.iter(|| register(black_box(&ios), black_box(&cbct), &def).expect("register"))
    });
    let paper = RegisterOptions::paper();
    g.bench_function("paper_14_teeth", |b| {
        b.iter(|| register(black_box(&ios), black_box(&cbct), &paper).expect("register"))
    });
    // `toothfuse demo --seed 85 --jaw lower --variant partial --ios-export rough`: teeth 44-47.
    let mut o = PhantomOptions {
        seed: 85,
        jaw: Jaw::Lower,
        variant: Variant::PartialArch,
        ..PhantomOptions::default()
    };
    o.realism.ios.rough = IosExport::Rough.roughness();
    let short = Phantom::generate(&o).expect("phantom");
    let (ios, cbct) = phantom_inputs(&short).expect("inputs");
    eprintln!("short arch: teeth {:?}", ios.keys().collect::<Vec<_>>());
    g.bench_function("default_short_arch_restarts", |b| {
        b.iter(|| register(black_box(&ios), black_box(&cbct), &def).expect("register"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
