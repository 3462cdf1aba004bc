#!/usr/bin/env bash
# The README's "Speed and memory" tables: per-stage criterion medians of `benches/stages.rs`
# (one column per input; the `fuse` row is the whole one-call fuse), the library fuse's wall
# time and peak heap (`examples/peak_memory.rs`) and the CLI's maximum RSS
# (`benches/peak_rss.sh`), with the date, commit and load average (the machine is shared:
# figures taken while other builds run are upper bounds).
#
# Usage: bash benches/table.sh [--no-bench]   (--no-bench: reuse target/criterion as it is)
# STAGES_INPUTS=clean_1x,f901_upper restricts the benchmark and the memory table to those inputs.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" != "--no-bench" ]; then
  echo "load before the benchmark: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
  cargo bench -p toothfuse-benches --bench stages >&2
fi
cargo build --release --example peak_memory >&2
echo "Measured $(date -u +%Y-%m-%d) at commit $(git rev-parse --short HEAD);" \
  "load average $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores."
echo
target/release/examples/peak_memory --stages target/criterion
echo
target/release/examples/peak_memory
echo
bash benches/peak_rss.sh
