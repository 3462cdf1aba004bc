//! Bit for bit the same whatever the thread count. Every parallel step of the library (the
//! phantom's per-tooth parts and grid waves, the registration's per-tooth preparation and gate
//! hypotheses, the cut and stitching of the teeth, the volume surfacing and split) takes as many
//! threads as the process may run on (`std::thread::available_parallelism`, at most 4). Each
//! test runs the same work with this thread pinned to one CPU (one thread: the plain sequential
//! order) and with every CPU it was allowed, and compares the results bit for bit. On a
//! one-CPU machine both runs take one thread; the tests say so.

use std::collections::BTreeMap;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant, VoxelizeOptions, voxelize};
use toothfuse::pipeline::{self, PipelineOptions, PipelineResult};
use toothfuse::volume::{SplitOptions, SurfaceOptions, VolumeScheme, split_teeth, surface_teeth};

/// Runs `f` with this thread's CPU affinity set to the first CPU it may run on (`one`) or left
/// as it is, restoring it afterwards; returns the result and the thread count the library saw.
fn on_cpus<R>(one: bool, f: impl FnOnce() -> R) -> (R, usize) {
    // SAFETY: `cpu_set_t` is plain data; the calls get its size and a valid pointer, and only
    // change the affinity of this thread (the threads it spawns inherit it).
    unsafe {
        let size = std::mem::size_of::<libc::cpu_set_t>();
        let mut allowed: libc::cpu_set_t = std::mem::zeroed();
        assert_eq!(libc::sched_getaffinity(0, size, &mut allowed), 0);
        if one {
            let first = (0..libc::CPU_SETSIZE as usize)
                .find(|&c| libc::CPU_ISSET(c, &allowed))
                .expect("an allowed CPU");
            let mut single: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(first, &mut single);
            assert_eq!(libc::sched_setaffinity(0, size, &single), 0);
        }
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
        let r = f();
        assert_eq!(libc::sched_setaffinity(0, size, &allowed), 0);
        (r, threads)
    }
}

/// Runs `f` on one CPU and on all, asserts the first saw one thread, and returns both results.
fn both<R>(what: &str, f: impl Fn() -> R) -> (R, R) {
    let (a, one) = on_cpus(true, &f);
    let (b, all) = on_cpus(false, &f);
    assert_eq!(one, 1, "{what}: pinned to one CPU");
    if all == 1 {
        eprintln!(
            "{what}: this machine lets the process run on one CPU only: both runs took one thread"
        );
    } else {
        eprintln!("{what}: one thread against {all}");
    }
    (a, b)
}

/// A mesh's position bits and triangles.
type MeshBits = (Vec<[u64; 3]>, Vec<[u32; 3]>);

fn mesh_bits(m: &TriMesh) -> MeshBits {
    (
        m.positions
            .iter()
            .map(|p| p.to_array().map(f64::to_bits))
            .collect(),
        m.triangles.clone(),
    )
}

fn teeth_bits(t: &BTreeMap<u8, TriMesh>) -> Vec<(u8, MeshBits)> {
    t.iter().map(|(&f, m)| (f, mesh_bits(m))).collect()
}

/// A rough export of a partial arch (a few teeth: the suite's time).
fn rough_options() -> PhantomOptions {
    let mut opts = PhantomOptions {
        seed: 4,
        jaw: Jaw::Upper,
        variant: Variant::PartialArch,
        ..Default::default()
    };
    opts.realism.ios.rough = IosExport::Rough.roughness();
    opts
}

/// The fused jaw, every fused tooth and the report (its timings left out).
type Fused = (String, MeshBits, Vec<i32>, Vec<u8>, Vec<(u8, MeshBits)>);

fn fused(r: &PipelineResult) -> Fused {
    let mut rep = r.report();
    rep.timing_ms.clear();
    (
        serde_json::to_string(&rep).expect("report"),
        mesh_bits(&r.jaw.mesh),
        r.jaw.labels.clone(),
        r.jaw.source.clone(),
        r.jaw
            .teeth
            .iter()
            .map(|(&f, t)| (f, mesh_bits(&t.mesh)))
            .collect(),
    )
}

#[test]
fn a_rough_phantom_is_generated_the_same_on_one_thread() {
    // Generated each time (the test suites' phantom cache would hand back the first jaw).
    let (a, b) = both("phantom", || {
        Phantom::generate_uncached(&rough_options()).expect("phantom")
    });
    assert_eq!(mesh_bits(&a.ios.mesh), mesh_bits(&b.ios.mesh));
    assert_eq!(a.ios.vertex_labels, b.ios.vertex_labels);
    assert_eq!(teeth_bits(&a.cbct), teeth_bits(&b.cbct));
}

#[test]
fn clean_and_rough_jaws_fuse_the_same_on_one_thread() {
    let rough = Phantom::generate(&rough_options()).expect("phantom");
    let clean = Phantom::generate(&PhantomOptions {
        seed: 4,
        jaw: Jaw::Upper,
        ..Default::default()
    })
    .expect("phantom");
    for (what, p) in [("clean jaw", &clean), ("rough jaw", &rough)] {
        let (a, b) = both(what, || {
            let r = pipeline::fuse(&p.ios, &p.cbct, &PipelineOptions::default()).expect(what);
            fused(&r)
        });
        assert!(a.4.len() >= 3, "{what}: {} teeth fused", a.4.len());
        assert!(a == b, "{what}: the one-thread fuse differs");
    }
}

#[test]
fn label_volumes_are_surfaced_and_split_the_same_on_one_thread() {
    let p = Phantom::generate(&PhantomOptions {
        seed: 5,
        jaw: Jaw::Upper,
        ..Default::default()
    })
    .expect("phantom");
    let per_tooth = voxelize(&p.cbct, &VoxelizeOptions::default()).expect("voxelize");
    let (a, b) = both("surfacing", || {
        let s = surface_teeth(&per_tooth, VolumeScheme::Fdi, &SurfaceOptions::default())
            .expect("surface");
        let meshes: BTreeMap<u8, TriMesh> = s.teeth.into_iter().map(|(f, t)| (f, t.mesh)).collect();
        teeth_bits(&meshes)
    });
    assert_eq!(a.len(), p.cbct.len());
    assert!(a == b, "surfacing: the one-thread surfaces differ");
    // One teeth class for the jaw (DentalSegmentator's upper teeth), split with the IOS crowns.
    let class = voxelize(
        &p.cbct,
        &VoxelizeOptions {
            class: Some(3),
            ..Default::default()
        },
    )
    .expect("voxelize");
    let crowns = toothfuse::fuse::ios_crowns(&p.ios).expect("crowns");
    let (a, b) = both("split", || {
        split_teeth(&class, &crowns, &SplitOptions::default())
            .expect("split")
            .volume
            .labels
    });
    assert!(
        a.iter().filter(|&&l| l > 10).count() > 1000,
        "teeth labelled"
    );
    assert!(a == b, "split: the one-thread labels differ");
}
