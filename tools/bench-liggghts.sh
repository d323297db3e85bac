#!/usr/bin/env bash
# The LIGGGHTS peer benchmark (tools/bench/liggghts): the Table 2 bed shaken at 5 mm, 30.8 Hz
# in a static cylinder with the shaking applied in the container's frame, one core, at the
# same time step pdamp's soft engine uses for data/scenarios/bench/table2_shaken.ini, so the
# figures compare with tools/bench-soft.sh. Installs Debian's liggghts if missing (root).
# Usage: tools/bench-liggghts.sh [--rounds R]   (env: SIZES, VARIANTS, VALIDATE as in run_bench.sh)
#   --rounds R   R rounds per size of: pdamp's shaken bed (periods 2-4, one thread), LIGGGHTS
#                (frame variant), pdamp again; prints each round's throughputs and the ratio
#                of pdamp's mean around it to LIGGGHTS's. A shared machine's speed drifts by tens
#                of per cent within minutes, so only runs this close to each other compare.
#                Every timed run is on one core (PDAMP_BENCH_CORE, see tools/bench-lib.sh).
#                SIZES defaults to 1246:10e-3 here.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=0
while (($#)); do
  case "$1" in
    --rounds)
      [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || { echo "--rounds '${2:-}': must be a whole number of rounds, 1 or more" >&2; exit 2; }
      rounds=$2; shift ;;
    *) echo "usage: tools/bench-liggghts.sh [--rounds R]" >&2; exit 2 ;;
  esac
  shift
done
"$root/tools/setup.sh"
command -v liggghts >/dev/null || { apt-get update -qq && apt-get install -y -qq liggghts python3 >/dev/null; }
"$root/tools/build.sh" release >/dev/null
source "$root/tools/bench-lib.sh"
dt=$("$pdamp" check --scenario "$root/data/scenarios/bench/table2_shaken.ini" |
     sed -n 's/^# soft engine time step: \([0-9.e+-]*\) s.*/\1/p')
work="$root/build/bench/liggghts"
rm -rf "$work" && mkdir -p "$work" && cp "$root"/tools/bench/liggghts/* "$work"/
echo "LIGGGHTS at pdamp's time step dt = $dt s"
if ((rounds == 0)); then
  VALIDATE=${VALIDATE:-0} DT="$dt" on_bench_core "$work/run_bench.sh"
  exit 0
fi

pdamp_throughput() {  # particles diameter_m
  local steps seconds peak_kB
  read -r steps seconds peak_kB < <(shaken_periods_2_to_4 "$1" "$2" 1)
  awk -v n="$1" -v s="$steps" -v w="$seconds" 'BEGIN { printf "%.4e", n * s / w }'
}
printf '%8s %6s %14s %14s %14s %7s\n' particles round pdamp_before liggghts pdamp_after ratio
for size in ${SIZES:-1246:10e-3}; do
  n=${size%%:*}; diameter=$(awk -v d="${size##*:}" 'BEGIN { printf "%.6f", d }')
  shaken "$n" "$diameter" --duration 0.0005 >/dev/null  # settles the bed once, untimed
  ratios=()
  for ((r = 1; r <= rounds; ++r)); do
    before=$(pdamp_throughput "$n" "$diameter")
    SIZES="$size" VARIANTS=frame VALIDATE=0 DT="$dt" on_bench_core "$work/run_bench.sh" >/dev/null
    liggghts=$(awk -F'\t' 'END { print $6 }' "$work/runs/results.tsv")
    after=$(pdamp_throughput "$n" "$diameter")
    ratio=$(awk -v a="$before" -v b="$after" -v l="$liggghts" 'BEGIN { printf "%.2f", (a + b) / 2 / l }')
    ratios+=("$ratio")
    printf '%8d %6d %14s %14s %14s %7s\n' "$n" "$r" "$before" "$liggghts" "$after" "$ratio"
  done
  printf '%s\n' "${ratios[@]}" | sort -n |
    awk -v n="$n" '{ a[NR] = $1 } END {
      printf "%8d ratio pdamp/LIGGGHTS: min %s, median %.2f, max %s (%d rounds)\n", n, a[1], (a[int((NR + 1) / 2)] + a[int(NR / 2) + 1]) / 2, a[NR], NR }'
done
