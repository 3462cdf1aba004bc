#!/usr/bin/env bash
# Fuzzes every cargo-fuzz target in fuzz/ for a bounded time (called by scripts/test.sh):
#   bash scripts/check_fuzz.sh            # FUZZ_SECONDS=20 per target by default
# Needs the nightly toolchain (libFuzzer instrumentation); without it, says so and skips.
# Installs cargo-fuzz when missing. Builds every target once (`cargo +nightly fuzz build`, with
# debug assertions, no sanitizer: the build stays within the test command's time), then runs them, up to $(nproc) at a time, each from a
# scratch copy of its seed corpus (fuzz/seeds/<target>; the repository is not changed) with:
#   -rss_limit_mb / -malloc_limit_mb 1024: a size declared in a header (PLY element counts, the STL
#     triangle count, VTK NumberOfPoints, ...) must be refused, not allocated;
#   -timeout 10 s per input (60 s for ffi_fuse, a whole registration + fuse): no hang;
#   -max_len: 16 KiB for file readers, 256 B (32 mutation records) for ffi_fuse.
# A crash, leak, OOM or timeout fails the run; the input is left in build/fuzz/artifacts/<target>/
# (reproduce with `fuzz/target/x86_64-unknown-linux-gnu/release/<target> <file>`). Keep each
# fixed input as a regression test in tests/fuzz_regressions/<target>/ (tests/fuzz_regressions.rs).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
SECONDS_PER_TARGET=${FUZZ_SECONDS:-20}
PARALLEL=${FUZZ_PARALLEL:-$(nproc 2>/dev/null || echo 2)}
CARGO_FUZZ_VERSION=0.13.2
WORK="$ROOT/build/fuzz"
TARGETS=(read_ply read_stl read_obj_labels read_vtp read_vtk_legacy ffi_fuse)

if ! rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
  echo "SKIPPED fuzzing: no nightly Rust toolchain (cargo-fuzz needs it: rustup toolchain install nightly)"
  exit 0
fi
if ! cargo fuzz --version 2>/dev/null | grep -q "$CARGO_FUZZ_VERSION"; then
  # A debug build: the wrapper only starts cargo, and it compiles in about half the time.
  cargo install cargo-fuzz --version "$CARGO_FUZZ_VERSION" --locked --force --debug
fi

START=$(date +%s)
echo "building ${#TARGETS[@]} fuzz targets (cargo +nightly fuzz build)"
cargo +nightly fuzz build --codegen-units 16 -s none
echo "built in $(($(date +%s) - START)) s; fuzzing each target ${SECONDS_PER_TARGET} s, ${PARALLEL} at a time"

BIN="$ROOT/fuzz/target/x86_64-unknown-linux-gnu/release"
rm -rf "$WORK"
mkdir -p "$WORK"
run_target() {
  local t=$1 max_len=16384
  local timeout=10
  [ "$t" = ffi_fuse ] && max_len=256 && timeout=60
  mkdir -p "$WORK/corpus/$t" "$WORK/artifacts/$t"
  cp fuzz/seeds/"$t"/* "$WORK/corpus/$t/"
  if "$BIN/$t" "$WORK/corpus/$t" -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=1024 \
      -malloc_limit_mb=1024 -timeout="$timeout" -max_len="$max_len" -print_final_stats=1 \
      -artifact_prefix="$WORK/artifacts/$t/" >"$WORK/$t.log" 2>&1; then
    echo "fuzz $t: ok ($(grep -o 'stat::number_of_executed_units: *[0-9]*' "$WORK/$t.log" |
      grep -o '[0-9]*$') runs, corpus $(ls "$WORK/corpus/$t" | wc -l) inputs)"
  else
    echo "fuzz $t: FAILED; log $WORK/$t.log, input in $WORK/artifacts/$t/:" >&2
    grep -E 'ERROR|panicked|SUMMARY|Test unit written' "$WORK/$t.log" | head -20 >&2
    return 1
  fi
}

failed=0
pids=()
names=()
for t in "${TARGETS[@]}"; do
  run_target "$t" & pids+=($!); names+=("$t")
  if [ ${#pids[@]} -ge "$PARALLEL" ]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done
if [ "$failed" -ne 0 ]; then
  echo "fuzzing found a failure (see above)" >&2
  exit 1
fi
echo "fuzzing: ${#TARGETS[@]} targets clean in $(($(date +%s) - START)) s"
