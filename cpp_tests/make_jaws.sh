#!/bin/sh
# Writes 20 synthetic jaws for the fusion checkers: OUT/jaw_<k> (k = 0..19) = seed k+1, variant
# k mod 5 (full, missing, partial, metal, drift), lower jaw for odd k, upper for even k.
#   sh make_jaws.sh TOOTHFUSE_CLI OUT
set -eu
cli=$1
out=$2
k=0
for _ in 1 2 3 4; do
  for variant in full missing partial metal drift; do
    jaw=upper
    if [ $((k % 2)) -eq 1 ]; then jaw=lower; fi
    "$cli" demo --seed $((k + 1)) --jaw "$jaw" --variant "$variant" --out "$out/jaw_$k" >/dev/null
    k=$((k + 1))
  done
done
echo "wrote $k jaws to $out"
