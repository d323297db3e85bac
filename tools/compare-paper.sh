#!/usr/bin/env bash
# "Results" in docs/comparison-and-results.md: the paper's cases on both models, into build/report/paper.sqlite
# (or --db FILE); each case settles its bed once and every later run starts from it.
#   - Table 1: pdamp compare with constant and with calibrated restitution (1.5 s);
#   - Table 2: pdamp compare, calibrated, first 0.05 s (the hard model is slow on this bed);
#   - Table 4: the soft model alone over each case's whole run, then pdamp compare,
#     calibrated, over 20 Hz's whole second and the first 0.2 s of the others; the hard
#     model alone (constant restitution) at 250 and 500 Hz, which the soft law cannot run;
#   - Table 1 with the experiment's host damping, soft model;
#   - pdamp compare with the hard model's settings for dense beds (docs/hard-engine.md,
#     "Settings for dense beds") on Table 1, Table 2's first 0.05 s, Table 4 at 20 Hz and
#     the first 0.2 s of the others.
# A case that fails is stored as failed and the script goes on. About 8 minutes on one quiet core (2026-12-05),
# and the dense settings' comparisons 2.2 min more (the sum of their runs, 2026-12-06).
# Usage: tools/compare-paper.sh [--db FILE] [--threads N]
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
db="$root/build/report/paper.sqlite"
threads=1
while (($#)); do
  case "$1" in
    --db) db=$2; shift ;;
    --threads) threads=$2; shift ;;
    *) echo "usage: tools/compare-paper.sh [--db FILE] [--threads N]" >&2; exit 2 ;;
  esac
  shift
done
"$root/tools/setup.sh" || exit 1
"$root/tools/build.sh" release >/dev/null || exit 1
mkdir -p "$(dirname "$db")"
pdamp() { echo "== pdamp $*"; "$root/build/release/src/pdamp" "$@" --threads "$threads" --db "$db"; }
scenario() { echo "$root/data/scenarios/$1.ini"; }

pdamp compare --scenario "$(scenario table1)" --set hard.restitution=constant
pdamp compare --scenario "$(scenario table1)" --set hard.restitution=calibrated
pdamp compare --scenario "$(scenario table2)" --set hard.restitution=calibrated --duration 0.05
for case_name in table4_packing95 table4_packing50 table4_packing25 table4_f20 table4_f100 table4_f250 table4_f500; do
  pdamp run --scenario "$(scenario "$case_name")" --model soft
done
pdamp compare --scenario "$(scenario table4_f20)" --set hard.restitution=calibrated
for case_name in table4_packing50 table4_packing95 table4_packing25 table4_f100; do
  pdamp compare --scenario "$(scenario "$case_name")" --set hard.restitution=calibrated --duration 0.2
done
for case_name in table4_f250 table4_f500; do
  pdamp run --scenario "$(scenario "$case_name")" --model hard --duration 0.2
done
pdamp run --scenario "$(scenario table1_experiment_damping)" --model soft
dense=(--set hard.restitution=calibrated --set hard.rest_tc_window=10 --set hard.elastic_speed_m_s=0.1)
pdamp compare --scenario "$(scenario table1)" "${dense[@]}"
pdamp compare --scenario "$(scenario table2)" "${dense[@]}" --duration 0.05
pdamp compare --scenario "$(scenario table4_f20)" "${dense[@]}"
for case_name in table4_packing95 table4_f100 table4_packing50 table4_packing25; do
  pdamp compare --scenario "$(scenario "$case_name")" "${dense[@]}" --duration 0.2
done
exit 0
