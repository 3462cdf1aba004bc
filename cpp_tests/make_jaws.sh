#!/bin/sh
# Writes 20 synthetic jaws for the fusion checkers: OUT/jaw_<k> (k = 0..19) = seed k+1, variant
# k mod 5 (full, missing, partial, metal, drift), lower jaw for odd k, upper for even k.
#   sh make_jaws.sh TOOTHFUSE_CLI OUT
# With a third argument `rough`, two rough IOS exports instead (raw slivers, folds, clipped
# margins, notches, holes, label noise): OUT/jaw_0 = seed 7 upper partial arch, rough export;
# OUT/jaw_1 = seed 8 lower arch with missing teeth, coarse (decimated-like) export.
# Two generators run side by side (even and odd k): generating a jaw is mostly one thread.
set -eu
cli=$1
out=$2
if [ "${3:-}" = rough ]; then
  "$cli" demo --seed 7 --jaw upper --variant partial --ios-export rough --out "$out/jaw_0" \
    >/dev/null &
  first=$!
  "$cli" demo --seed 8 --jaw lower --variant missing --ios-export coarse --out "$out/jaw_1" \
    >/dev/null
  wait "$first"
  echo "wrote 2 rough jaws to $out"
  exit 0
fi
variants="full missing partial metal drift"
# make_half PARITY: the jaws whose k has that parity (even k: upper jaw, odd k: lower jaw).
make_half() {
  k=$1
  jaw=upper
  if [ "$1" -eq 1 ]; then jaw=lower; fi
  while [ "$k" -lt 20 ]; do
    variant=$(echo $variants | cut -d' ' -f$((k % 5 + 1)))
    "$cli" demo --seed $((k + 1)) --jaw "$jaw" --variant "$variant" --out "$out/jaw_$k" >/dev/null
    k=$((k + 2))
  done
}
make_half 0 &
even=$!
make_half 1 &
odd=$!
status=0
wait "$even" || status=1
wait "$odd" || status=1
if [ "$status" -ne 0 ]; then
  echo "make_jaws.sh: a jaw could not be generated" >&2
  exit 1
fi
echo "wrote 20 jaws to $out"
