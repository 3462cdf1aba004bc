//! Running the `toothfuse` binary from the CLI tests: its output, a success asserted with its
//! streams shown on failure, and scratch folders.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary run with `args`.
pub fn tf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_toothfuse"))
        .args(args)
        .output()
        .expect("run toothfuse")
}

/// The binary run with `args`, asserted to succeed: its standard output.
pub fn ok(args: &[&str]) -> String {
    let o = tf(args);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    );
    assert!(o.status.success(), "{args:?} failed:\n{out}\n{err}");
    out
}

/// An empty scratch folder for the test `name` (this process's own).
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("toothfuse_cli_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A path as text (the tests' paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
