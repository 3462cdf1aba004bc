#!/usr/bin/env bash
# Maximum resident set size and wall time of the `toothfuse fuse` command-line process (read
# both PLY files, register, cut, stitch, write fused.ply, tooth_<fdi>.ply and report.json), as
# /usr/bin/time -v reports them, on:
#   - the synthetic jaw written by `toothfuse demo` (seed 1, upper) as the clean scan and as
#     the rough exports at 1x, 2x and 4x the vertex density;
#   - the foreign jaws (`ios.ply` = labelled IOS jaw, `cbct.ply` = labelled CBCT teeth) from
#     $TOOTHFUSE_FOREIGN_DATA or shared/data/foreign beside the checkout (skipped with a
#     message when absent).
# Prints a markdown table; MB = 10^6 bytes. Usage: bash benches/peak_rss.sh [INPUT ...] with
# INPUT among clean rough dense2 dense4 f901_upper f902_lower (default: all).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (GNU time)" >&2; exit 1; }
cargo build --release --bin toothfuse >&2
bin=target/release/toothfuse
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

foreign=""
for d in "${TOOTHFUSE_FOREIGN_DATA:-}" ../shared/data/foreign ../../shared/data/foreign \
         /work/shared/data/foreign; do
  if [ -n "$d" ] && [ -d "$d" ]; then foreign=$d; break; fi
done

inputs=("$@")
[ ${#inputs[@]} -gt 0 ] || inputs=(clean rough dense2 dense4 f901_upper f902_lower)

# Vertex count from a PLY header.
vertices() { head -c 2000 "$1" | grep -a -m1 '^element vertex' | awk '{print $3}'; }

echo "| input | IOS vertices | CLI wall s | CLI max RSS (MB) |"
echo "|---|---|---|---|"
for input in "${inputs[@]}"; do
  case $input in
    clean|rough|dense2|dense4)
      "$bin" demo --ios-export "$input" --out "$tmp/$input" >/dev/null
      dir=$tmp/$input ;;
    *)
      if [ -z "$foreign" ] || [ ! -f "$foreign/$input/ios.ply" ]; then
        echo "SKIPPED $input: foreign jaw not found (set TOOTHFUSE_FOREIGN_DATA)" >&2
        continue
      fi
      dir=$foreign/$input ;;
  esac
  /usr/bin/time -v -o "$tmp/time.txt" "$bin" fuse --ios "$dir/ios.ply" --cbct "$dir/cbct.ply" \
    --out "$tmp/out_$input" >"$tmp/fuse.txt" 2>&1 || { cat "$tmp/fuse.txt" >&2; exit 1; }
  rss_kb=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$tmp/time.txt")
  wall=$(awk '/Elapsed \(wall clock\)/ {print $NF}' "$tmp/time.txt")
  secs=$(echo "$wall" | awk -F: '{ s = 0; for (i = 1; i <= NF; i++) s = s * 60 + $i; print s }')
  printf "| %s | %s | %.2f | %.0f |\n" "$input" "$(vertices "$dir/ios.ply")" "$secs" \
    "$(echo "$rss_kb" | awk '{print $1 * 1024 / 1e6}')"
  rm -rf "$tmp/out_$input"
done
