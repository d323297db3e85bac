#!/usr/bin/env bash
# What checkpoints cost (docs/checkpoints.md): Table 1 on each model with
# --checkpoint-every 0 (none), 60 (the default: the run's last state, and one a minute),
# 1 (one a second) and 0.05 (twenty a second, so that their cost stands out of the
# machine's noise), alternated round by round on one core (PDAMP_BENCH_CORE,
# tools/bench-lib.sh). Prints each run's wall time (the runs table's, the run itself: the
# bed is settled once beforehand and shared), then per model and setting the median, min
# and max, the median's change against none, and the checkpoints' size; last, per model,
# what one checkpoint costs: the 0.05 s runs' extra wall time over none, round by round,
# divided by the checkpoints they took (about their wall time / 0.05 s), and what that
# makes of a minute, the default interval.
# Usage: tools/bench-checkpoint.sh [--rounds N] [--soft-duration S] [--hard-duration S]
#   defaults: 5 rounds, soft 0.15 s of Table 1 (a tenth: 1.5 s takes 1.5 min a run), hard 1.5 s
# PDAMP_BINARY picks the pdamp to time (default build/release/src/pdamp, built first).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=5
soft_duration=0.15
hard_duration=1.5
while [ $# -gt 0 ]; do
  case $1 in
    --rounds) rounds=$2; shift 2 ;;
    --soft-duration) soft_duration=$2; shift 2 ;;
    --hard-duration) hard_duration=$2; shift 2 ;;
    *) echo "tools/bench-checkpoint.sh: unknown option '$1' (valid: --rounds N, --soft-duration S, --hard-duration S)" >&2
       exit 2 ;;
  esac
done
source "$root/tools/bench-lib.sh"
pdamp_and_store checkpoint
table1="$root/data/scenarios/table1.ini"
pin=(on_bench_core)
# The shared bed, settled once.
run --scenario "$table1" --model hard --duration 0.001 --checkpoint-every 0 >/dev/null

results=$(mktemp)
for round in $(seq "$rounds"); do
  for model in soft hard; do
    duration=$soft_duration
    [ "$model" = hard ] && duration=$hard_duration
    for every in 0 60 1 0.05; do
      id=$(run --scenario "$table1" --model "$model" --duration "$duration" --checkpoint-every "$every" --threads 1)
      bytes=$(sqlite3 "$db" "SELECT coalesce(length(state), 0) FROM runs LEFT JOIN run_checkpoints USING (run_id) WHERE run_id = $id")
      echo "$model $every $round $(wall "$id") $bytes" | tee -a "$results"
    done
  done
done
echo
# Each setting against none of the same round (the machine's speed drifts between rounds).
echo "model every_s runs wall_median_s wall_min_s wall_max_s ratio_to_none_median ratio_min ratio_max checkpoint_bytes"
for model in soft hard; do
  for every in 0 60 1 0.05; do
    paired=$(awk -v m=$model -v e=$every '$1 == m && $2 == 0 { none[$3] = $4 } $1 == m && $2 == e { t[$3] = $4; b = $5 }
      END { for (r in t) print t[r], t[r] / none[r], b }' "$results")
    echo "$model $every $(echo "$paired" | wc -l) $(echo "$paired" | cut -d' ' -f1 | median_min_max)" \
      "$(echo "$paired" | cut -d' ' -f2 | median_min_max) $(echo "$paired" | head -1 | cut -d' ' -f3)"
  done
done
echo
echo "model checkpoint_ms_median checkpoint_ms_min checkpoint_ms_max percent_of_a_minute_median"
for model in soft hard; do
  per=$(awk -v m=$model '$1 == m && $2 == 0 { none[$3] = $4 } $1 == m && $2 == 0.05 { t[$3] = $4 }
    END { for (r in t) printf "%.4f\n", 1000 * (t[r] - none[r]) / (t[r] / 0.05) }' "$results" | median_min_max)
  echo "$model $per $(echo "$per" | awk '{ printf "%.4f", $1 / 600 }')"
done
rm -f "$results"
