//! The registration gate's scores on phantoms: each seed's own IOS and CBCT (valid), the
//! previous seed's IOS with this seed's CBCT (`other`) and this seed's IOS with the previous
//! seed's CBCT (`other'`: another patient). The figures of docs/errors.md.
//!
//! `GATE_DEBUG=1` prints each whole report (`{:?}`, full precision) instead of the summary.
//!
//! `cargo run --release --example gate_scores -- FIRST_SEED LAST_SEED JAW(0 upper, 1 lower)
//! VARIANT(0 full, 1 missing, 2 partial, 3 metal, 4 drift)`
use toothfuse::arch::Jaw;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::register::{GateReport, RegisterOptions, register};

fn stats(g: &GateReport) -> String {
    if std::env::var_os("GATE_DEBUG").is_some() {
        return format!("{g:?}");
    }
    let mut tr: Vec<f64> = g.teeth.iter().map(|e| e.own_motion[0].length()).collect();
    tr.sort_by(f64::total_cmp);
    let mut e: Vec<_> = g.teeth.iter().collect();
    e.sort_by_key(|x| toothfuse::arch::arch_position(x.fdi));
    let mut r: Vec<f64> = e
        .windows(3)
        .map(|w| (w[1].own_motion[0] - 0.5 * (w[0].own_motion[0] + w[2].own_motion[0])).length())
        .collect();
    r.sort_by(f64::total_cmp);
    format!(
        "mismatch {:.3} fit {:.3} offset {:.3} trans {:.3} refit {:.3} mir {:.3} shift {:.3} toothshift {:.3} rough {:.3} trans_med {:.3} trans_rough {:.3} gate {:.0}ms",
        g.mismatch,
        g.fit_mm,
        g.surface_offset_mm,
        g.tooth_translation_mm,
        g.refit_mm,
        g.mirrored_fit_mm,
        g.shifted_fit_mm,
        g.tooth_shift_mm,
        g.roughness_mm,
        tr[tr.len() / 2],
        r[r.len() / 2],
        0.0
    )
}

fn main() {
    let a: Vec<u64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let jaw = if a[2] == 0 { Jaw::Upper } else { Jaw::Lower };
    let variant = Variant::ALL[a[3] as usize];
    let mut prev: Option<Phantom> = None;
    for seed in a[0]..=a[1] {
        let p = Phantom::generate(&PhantomOptions {
            seed,
            jaw,
            variant,
            ..Default::default()
        })
        .unwrap();
        let mut o = RegisterOptions::default().without_fine();
        o.coarse = None;
        o.accept_questionable = true;
        let Ok(r) = register(&p.ios_crowns(), &p.cbct, &o) else {
            println!("{seed} {variant:?}: fewer than 3 teeth in both, skipped");
            prev = Some(p);
            continue;
        };
        println!(
            "{seed} {variant:?} valid: {} t {:.0}",
            stats(&r.gate),
            r.timing.gate_ms
        );
        if let Some(q) = &prev
            && let Ok(r) = register(&q.ios_crowns(), &p.cbct, &o)
        {
            println!("{seed} other: {} t {:.0}", stats(&r.gate), r.timing.gate_ms);
        }
        if let Some(q) = &prev
            && let Ok(r) = register(&p.ios_crowns(), &q.cbct, &o)
        {
            println!(
                "{seed} other': {} t {:.0}",
                stats(&r.gate),
                r.timing.gate_ms
            );
        }
        prev = Some(p);
    }
}
