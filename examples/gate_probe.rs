use std::collections::BTreeMap;
use std::time::Instant;
use toothfuse::arch::{Jaw, arch_order};
use toothfuse::mesh::TriMesh;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::register::{RegisterOptions, register};

fn shifted(c: &BTreeMap<u8, TriMesh>) -> BTreeMap<u8, TriMesh> {
    let order = arch_order(&c.keys().copied().collect::<Vec<_>>());
    (0..order.len() - 1)
        .map(|k| (order[k + 1], c[&order[k]].clone()))
        .collect()
}
fn swapped(c: &BTreeMap<u8, TriMesh>) -> BTreeMap<u8, TriMesh> {
    let mut m = c.clone();
    let ks: Vec<u8> = m.keys().copied().collect();
    let (x, y) = (ks[3], ks[4]);
    let a = m.remove(&x).unwrap();
    let b = m.remove(&y).unwrap();
    m.insert(x, b);
    m.insert(y, a);
    m
}
fn mirrored(c: &BTreeMap<u8, TriMesh>) -> BTreeMap<u8, TriMesh> {
    c.iter()
        .map(|(&f, m)| {
            let mut m = m.clone();
            for p in &mut m.positions {
                p.x = -p.x;
            }
            for t in &mut m.triangles {
                t.swap(1, 2);
            }
            (f, m)
        })
        .collect()
}

fn run(name: &str, ios: &BTreeMap<u8, TriMesh>, cbct: &BTreeMap<u8, TriMesh>) {
    let t = Instant::now();
    let mut o = RegisterOptions::default().without_fine();
    o.coarse = None;
    o.accept_questionable = true;
    match register(ios, cbct, &o) {
        Ok(r) => {
            let g = &r.gate;
            let sds: Vec<String> = g
                .teeth
                .iter()
                .map(|e| {
                    format!(
                        "{}:{:.2}/{:?}/{:.2}",
                        e.fdi,
                        e.own_fit_mm,
                        e.best_other.map(|(f, d)| (f, (d * 100.0).round() / 100.0)),
                        e.own_shift_mm
                    )
                })
                .collect();
            println!(
                "{name}: {:.2}s gate {:.0}ms fit {:.3} mir {:.3} shift {:.3} toothshift {:.3} rough {:.3} hand {:?} skip {} acc {}",
                t.elapsed().as_secs_f64(),
                r.timing.gate_ms,
                g.fit_mm,
                g.mirrored_fit_mm,
                g.shifted_fit_mm,
                g.tooth_shift_mm,
                g.roughness_mm,
                g.ios_handed_ok,
                sds.len(),
                g.accepted.len()
            );
        }
        Err(e) => println!("{name}: error {e}"),
    }
}

fn main() {
    let seeds: Vec<u64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    for &seed in &seeds {
        for jaw in [Jaw::Upper, Jaw::Lower] {
            let p = Phantom::generate(&PhantomOptions {
                seed,
                jaw,
                variant: Variant::Full,
                ..Default::default()
            })
            .unwrap();
            let q = Phantom::generate(&PhantomOptions {
                seed: seed + 100,
                jaw,
                variant: Variant::Full,
                ..Default::default()
            })
            .unwrap();
            let c = p.ios_crowns();
            run(&format!("{seed} valid"), &c, &p.cbct);
            run(&format!("{seed} other"), &q.ios_crowns(), &p.cbct);
            run(&format!("{seed} shifted"), &shifted(&c), &p.cbct);
            run(&format!("{seed} swapped"), &swapped(&c), &p.cbct);
            run(&format!("{seed} mirrored"), &mirrored(&c), &p.cbct);
            run(&format!("{seed} mirroredcbct"), &c, &mirrored(&p.cbct));
            for v in [
                Variant::MissingTeeth,
                Variant::PartialArch,
                Variant::MetalArtefact,
                Variant::HeavyDrift,
            ] {
                let p = Phantom::generate(&PhantomOptions {
                    seed,
                    jaw,
                    variant: v,
                    ..Default::default()
                })
                .unwrap();
                run(&format!("{seed} {v:?} valid"), &p.ios_crowns(), &p.cbct);
            }
        }
    }
}
