#!/usr/bin/env bash
# Reduced-order model benchmark (docs/rom.md, "Benchmark"): a 200-point predicted curve on the
# synthetic 8 x 10 lift-off table (data/rom/synthetic_liftoff.csv) for the Table 1 host
# (M = 0.0376 kg, K = 470 N/m, C = 0.01 N s/m), F0 = 0.05 N, 12 to 26 Hz, which crosses the
# three-solution region. Prints, over ROUNDS runs on one core (PDAMP_BENCH_CORE, see
# tools/bench-lib.sh), the smallest, median and largest of
#   - the prediction (pdamp rom --time: interpolation, harmonic balance, branches, sweeps);
#   - the whole command (process start, reading the table, predicting, writing CSV and JSON).
# Usage: tools/bench-rom.sh [ROUNDS]   (default 20)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=${1:-20}
if ! [[ $rounds =~ ^[1-9][0-9]*$ ]]; then
  echo "tools/bench-rom.sh: ROUNDS '$rounds': must be a whole number >= 1" >&2
  exit 2
fi
source "$root/tools/bench-lib.sh"
"$root/tools/build.sh" release >/dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for ((i = 0; i < rounds; i++)); do
  start=$(date +%s%N)
  on_bench_core "$pdamp" rom --table "$root/data/rom/synthetic_liftoff.csv" --mass 0.0376 --stiffness 470 \
    --damping 0.01 --force 0.05 --freq 12:26:200 --quiet --time --out "$work/p.csv" --out "$work/p.json" \
    2>>"$work/predict"
  end=$(date +%s%N)
  echo "$(((end - start) / 1000))" >>"$work/wall_us"
done
summary() { sort -g | awk '{ v[NR] = $1 } END { printf "min %.3f  median %.3f  max %.3f ms\n", v[1], v[int((NR + 1) / 2)], v[NR] }'; }
echo "200-point curve, 8 x 10 table, $rounds runs on core $bench_core:"
printf "  prediction     "
sed -n 's/.* predicted in \([0-9.e+-]*\) ms$/\1/p' "$work/predict" | summary
printf "  whole command  "
awk '{ print $1 / 1000 }' "$work/wall_us" | summary
