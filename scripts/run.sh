#!/usr/bin/env bash
# The main job: build in release, write the synthetic jaw to files, fuse it through the real CLI
# path (file round trip) and print a summary. Exits non-zero on any failure (`toothfuse fuse`
# itself fails when a fused tooth is not watertight).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release
bin=target/release/toothfuse
"$bin" demo --out out/demo
"$bin" fuse --ios out/demo/ios.ply --cbct out/demo/cbct.ply --out out/fused | tee out/fused.log
n=$(grep -c '"watertight": true' out/fused/report.json)
echo "summary: $(grep '^fused ' out/fused.log); report.json lists $n watertight teeth; outputs in out/fused/"
