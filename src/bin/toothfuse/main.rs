//! `toothfuse` command-line tool.
fn main() {}
