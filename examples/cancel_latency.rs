//! How soon a cancel from the progress callback ends a whole fuse: per input, the fuse is run
//! once per report of a first run (cancelling at the k-th report, k = 1, 2, ...) and the time
//! from the callback's answer to the call's return is taken; prints the median and the largest
//! over the runs that reached their k-th report.
//!
//! `cargo run --release --example cancel_latency [INPUT ...]` (inputs of
//! `benches/common/inputs.rs`: clean_1x, rough_1x, dense2_2x, dense4_4x, f901_upper,
//! f902_lower; default clean_1x rough_1x f901_upper).
#[path = "../benches/common/inputs.rs"]
mod inputs;

use std::cell::{Cell, RefCell};
use std::ops::ControlFlow;
use std::rc::Rc;
use std::time::Instant;
use toothfuse::pipeline::{self, PipelineOptions};
use toothfuse::progress::with_progress;

fn main() {
    let mut names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() {
        names = ["clean_1x", "rough_1x", "f901_upper"]
            .map(String::from)
            .to_vec();
    }
    let opts = PipelineOptions::default();
    for name in names {
        let Some(&(_, src)) = inputs::selected().iter().find(|(n, _)| *n == name) else {
            eprintln!("{name}: unknown input");
            continue;
        };
        let Some(input) = inputs::load(&name, src) else {
            continue;
        };
        // The reports of a whole run.
        let count = Rc::new(Cell::new(0usize));
        let c = Rc::clone(&count);
        let whole = Instant::now();
        with_progress(
            move |_| {
                c.set(c.get() + 1);
                ControlFlow::Continue(())
            },
            || pipeline::fuse(&input.ios, &input.cbct, &opts),
        )
        .expect("fuse");
        let whole_ms = whole.elapsed().as_secs_f64() * 1e3;
        let mut delays = Vec::new();
        for k in 1..count.get() {
            let seen = Rc::new(Cell::new(0usize));
            let asked: Rc<RefCell<Option<Instant>>> = Rc::default();
            let (s, a) = (Rc::clone(&seen), Rc::clone(&asked));
            let r = with_progress(
                move |_| {
                    s.set(s.get() + 1);
                    if s.get() == k {
                        *a.borrow_mut() = Some(Instant::now());
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                },
                || pipeline::fuse(&input.ios, &input.cbct, &opts),
            );
            let end = Instant::now();
            // The reports between band builds come from the teeth the calling thread takes,
            // which vary from run to run: a run may end before its k-th report.
            let Some(at) = *asked.borrow() else {
                continue;
            };
            assert!(
                r.is_err(),
                "{name}: the cancel at report {k} was not answered"
            );
            delays.push((end - at).as_secs_f64() * 1e3);
        }
        delays.sort_by(f64::total_cmp);
        println!(
            "{name}: whole fuse {whole_ms:.0} ms, {} reports; cancel to return over {} runs: median {:.1} ms, largest {:.1} ms",
            count.get(),
            delays.len(),
            delays[delays.len() / 2],
            delays[delays.len() - 1]
        );
    }
}
