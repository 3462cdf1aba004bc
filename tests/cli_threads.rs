//! `toothfuse --threads N`: the cap on the threads of the whole process. Under `--threads 1`
//! the process never runs a second thread, under `--threads 2` never a third (its thread count
//! watched in /proc while it fuses), and its files are those of an uncapped run, byte for byte
//! (report.json but its timings). `toothfuse --progress`: the steps on stderr, the same files.

mod cli_common;

use cli_common::tmp;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Runs the binary with `args` to completion; returns whether it succeeded and the most
/// threads its /proc entry showed while it ran (sampled about every 0.2 ms).
fn run_watching_threads(args: &[&str]) -> (bool, usize) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_toothfuse"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run toothfuse");
    let status = format!("/proc/{}/status", child.id());
    let mut most = 0;
    loop {
        if let Ok(text) = std::fs::read_to_string(&status)
            && let Some(n) = text
                .lines()
                .find_map(|l| l.strip_prefix("Threads:"))
                .and_then(|n| n.trim().parse::<usize>().ok())
        {
            most = most.max(n);
        }
        if let Some(exit) = child.try_wait().expect("wait") {
            return (exit.success(), most);
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
}

fn files(d: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            let mut bytes = std::fs::read(&p).unwrap();
            if name == "report.json" {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                v["timing_ms"] = serde_json::Value::Null;
                bytes = serde_json::to_vec(&v).unwrap();
            }
            (name, bytes)
        })
        .collect();
    out.sort();
    out
}

/// Writes the demo jaw of these tests (seed 6, a partial arch) into `d/demo`; returns its IOS
/// and CBCT files.
fn demo_jaw(d: &Path) -> (PathBuf, PathBuf) {
    let demo = d.join("demo");
    let (ok, _) = run_watching_threads(&[
        "demo",
        "--seed",
        "6",
        "--variant",
        "partial",
        "--out",
        demo.to_str().unwrap(),
    ]);
    assert!(ok, "demo");
    (demo.join("ios.ply"), demo.join("cbct.ply"))
}

#[test]
fn one_thread_runs_alone_and_writes_the_same_files() {
    let d = tmp("threads");
    let (ios, cbct) = demo_jaw(&d);
    let fuse = |out: &Path, threads: &str| {
        run_watching_threads(&[
            "--threads",
            threads,
            "fuse",
            "--labels",
            "fdi",
            "--ios",
            ios.to_str().unwrap(),
            "--cbct",
            cbct.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let (one, free) = (d.join("one"), d.join("free"));
    let (ok, most) = fuse(&one, "1");
    assert!(ok, "fuse --threads 1");
    assert_eq!(most, 1, "--threads 1: {most} threads seen");
    let (two, free) = (d.join("two"), free);
    let (ok, most) = fuse(&two, "2");
    assert!(ok, "fuse --threads 2");
    assert!(most <= 2, "--threads 2: {most} threads seen");
    let (ok, most) = fuse(&free, "0");
    assert!(ok, "fuse");
    eprintln!("uncapped: up to {most} threads seen");
    assert_eq!(files(&two), files(&free), "--threads 2");
    let (a, b) = (files(&one), files(&free));
    assert!(a.len() >= 5, "{} files", a.len());
    assert_eq!(
        a.iter().map(|f| &f.0).collect::<Vec<_>>(),
        b.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} differs");
    }
    // The cap is a number.
    let (ok, _) = run_watching_threads(&["--threads", "many", "demo", "--out", "x"]);
    assert!(!ok, "--threads many is refused");
    let _ = std::fs::remove_dir_all(&d);
}

/// `--progress` prints each stage's steps on stderr in order, from 0 to the stage's total, and
/// the files are those of a run without it.
#[test]
fn progress_lines_come_in_stage_order_and_change_no_file() {
    let d = tmp("progress");
    let bin = env!("CARGO_BIN_EXE_toothfuse");
    let out = |args: &[&str]| {
        let o = Command::new(bin)
            .args(args)
            .output()
            .expect("run toothfuse");
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stderr).unwrap()
    };
    let (ios, cbct) = demo_jaw(&d);
    let (with, without) = (d.join("with"), d.join("without"));
    let fuse = |dir: &Path, extra: &[&str]| {
        let mut args = extra.to_vec();
        args.extend(["fuse", "--labels", "fdi", "--ios", ios.to_str().unwrap()]);
        args.extend([
            "--cbct",
            cbct.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ]);
        out(&args)
    };
    let stderr = fuse(&with, &["--progress"]);
    let quiet = fuse(&without, &[]);
    assert!(!quiet.contains("toothfuse: stitch"), "{quiet}");
    assert_eq!(files(&with), files(&without));
    // (stage rank, done, total) of each progress line.
    let steps: Vec<(usize, usize, usize)> = stderr
        .lines()
        .filter_map(|l| {
            let mut w = l.strip_prefix("toothfuse: ")?.split([' ', '/']);
            let name = w.next()?;
            let stage = ["register", "cut", "stitch"]
                .iter()
                .position(|s| *s == name)?;
            Some((stage, w.next()?.parse().ok()?, w.next()?.parse().ok()?))
        })
        .collect();
    assert!(steps.windows(2).all(|w| w[0] < w[1]), "{stderr}");
    for stage in 0..3 {
        let of: Vec<_> = steps.iter().filter(|s| s.0 == stage).collect();
        assert!(!of.is_empty(), "stage {stage}: {stderr}");
        assert_eq!(of[0].1, 0, "{stderr}");
        assert_eq!(of.last().map(|s| s.1), Some(of[0].2), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
