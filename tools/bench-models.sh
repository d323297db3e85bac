#!/usr/bin/env bash
# The hard model against the soft one on the paper's cases (docs/hard-engine.md, "Against
# the soft model, alternated on one core"; issue 27's target): each case from its settled
# bed (settled once, in a first pass that is not timed), calibrated restitution, the soft
# model on one thread; the two models' runs one after the other on one core
# (PDAMP_BENCH_CORE, tools/bench-lib.sh), their order reversed every round. With
# --hard-set KEY=VALUE a second hard run per case and round with that setting (e.g.
# hard.rest_speed_m_s=0.05; repeated, one run with all of them); with --baseline PDAMP a
# hard run per case and round by that other pdamp binary (an engine before a change: its
# "soft / this" against the same soft runs). Prints every run, then per case and model the median (min–max)
# of the run's wall time (the runs table's: the run itself), the soft model's time over the
# hard one's taken round by round, and the particles' dissipation (impact and friction, at
# the run's end) against the soft model's, which is the same every round.
# Usage: tools/bench-models.sh [--rounds N] [--cases "NAME:DURATION_S ..."] [--hard-set KEY=VALUE]...
#                              [--baseline PDAMP]
#   defaults: 3 rounds; table2:0.05 table4_packing95:0.2 table4_packing50:0.2
#   table4_packing25:0.2 table4_f100:0.2 table4_f20:1 (data/scenarios/NAME.ini)
# PDAMP_BINARY picks the pdamp to time (default build/release/src/pdamp, built first).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=3
cases="table2:0.05 table4_packing95:0.2 table4_packing50:0.2 table4_packing25:0.2 table4_f100:0.2 table4_f20:1"
hard_set=()
baseline=""
usage="usage: tools/bench-models.sh [--rounds N] [--cases \"NAME:DURATION_S ...\"] [--hard-set KEY=VALUE]... [--baseline PDAMP]"
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || { echo "$usage ('$1' needs a value)" >&2; exit 2; }
  case $1 in
    --rounds) rounds=$2 ;;
    --cases) cases=$2 ;;
    --hard-set) hard_set+=(--set "$2") ;;
    --baseline) baseline=$2 ;;
    *) echo "$usage (unknown option '$1')" >&2; exit 2 ;;
  esac
  shift 2
done
[[ $rounds =~ ^[1-9][0-9]*$ ]] || { echo "tools/bench-models.sh: --rounds '$rounds' must be a whole number >= 1" >&2; exit 2; }
for c in $cases; do
  name=${c%%:*}
  [ -f "$root/data/scenarios/$name.ini" ] && [[ $c == *:* ]] || {
    echo "tools/bench-models.sh: case '$c' must be NAME:DURATION_S with data/scenarios/NAME.ini present" >&2
    exit 2
  }
done
if [ -n "$baseline" ] && [ ! -x "$baseline" ]; then
  echo "tools/bench-models.sh: --baseline '$baseline' is not an executable pdamp" >&2
  exit 2
fi
source "$root/tools/bench-lib.sh"
pdamp_and_store models

# One run of case $1 (NAME:DURATION) on model $2 (soft, hard, hard+ for --hard-set or
# baseline for the --baseline binary's hard model): its run id.
case_run() {
  local name=${1%%:*} duration=${1#*:} model=$2
  local extra=(--set hard.restitution=calibrated)
  [ "$model" = "hard+" ] && extra+=("${hard_set[@]}")
  # run (tools/bench-lib.sh) runs $pdamp: the baseline's runs see the other binary.
  [ "$model" = baseline ] && local pdamp=$baseline && model=hard
  run --scenario "$root/data/scenarios/$name.ini" --model "${model%+}" --duration "$duration" --threads 1 \
    --checkpoint-every 0 "${extra[@]}"
}
models=(soft hard)
[ ${#hard_set[@]} -gt 0 ] && models+=("hard+")
[ -n "$baseline" ] && models+=(baseline)

# Settles each case's bed and calibrates its restitution, untimed (a run of 1 ms is enough).
for c in $cases; do case_run "${c%%:*}:0.001" hard >/dev/null; done

pin=(on_bench_core)
results=$(mktemp)
trap 'rm -f "$results"' EXIT
dissipated() { sqlite3 "$db" "SELECT dissipated_impact_J + dissipated_friction_J FROM run_summary WHERE run_id = $1"; }
for round in $(seq "$rounds"); do
  order=("${models[@]}")
  ((round % 2)) || order=($(printf '%s\n' "${models[@]}" | tac))
  for c in $cases; do
    for model in "${order[@]}"; do
      id=$(case_run "$c" "$model")
      [ -n "$id" ] || { echo "tools/bench-models.sh: $c on $model did not run (pdamp run's message: run it by hand)" >&2; exit 1; }
      echo "${c%%:*} $model $round $(wall "$id") $(dissipated "$id")" | tee -a "$results"
    done
  done
done
echo
[ ${#hard_set[@]} -gt 0 ] && echo "hard+: hard with ${hard_set[*]}"
[ -n "$baseline" ] && echo "baseline: hard by $baseline"
echo "case model runs wall_median_s wall_min_s wall_max_s soft_over_this_median soft_over_this_min soft_over_this_max dissipation_vs_soft"
for c in $cases; do
  name=${c%%:*}
  for model in "${models[@]}"; do
    paired=$(awk -v c="$name" -v m="$model" '$1 == c && $2 == "soft" { soft[$3] = $4; ds = $5 }
      $1 == c && $2 == m { t[$3] = $4; d = $5 }
      END { for (r in t) printf "%s %s %+.4f\n", t[r], soft[r] / t[r], ds ? d / ds - 1 : 0 }' "$results")
    echo "$name $model $(echo "$paired" | wc -l) $(echo "$paired" | cut -d' ' -f1 | median_min_max)" \
      "$(echo "$paired" | cut -d' ' -f2 | median_min_max) $(echo "$paired" | head -1 | cut -d' ' -f3)"
  done
done
