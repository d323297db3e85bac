#!/usr/bin/env bash
# The comparator's report (README "Results"): `pdamp compare` on the paper's Table 1,
# Table 2 and the seven Table 4 cases, each with constant and with calibrated hard-sphere
# restitution, stored in build/report/paper.sqlite (or --db FILE). Settled beds are stored
# with the runs, so each case settles once. About an hour on one core.
# Usage: tools/compare-paper.sh [--db FILE] [--threads N] [case ...]   (case: table1, table4_f20, ...)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
db="$root/build/report/paper.sqlite"
threads=1
cases=()
while (($#)); do
  case "$1" in
    --db) db=$2; shift ;;
    --threads) threads=$2; shift ;;
    -*) echo "usage: tools/compare-paper.sh [--db FILE] [--threads N] [case ...]" >&2; exit 2 ;;
    *) cases+=("$1") ;;
  esac
  shift
done
((${#cases[@]})) || cases=(table1 table2 table4_packing95 table4_packing50 table4_packing25
                           table4_f20 table4_f100 table4_f250 table4_f500)
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
mkdir -p "$(dirname "$db")"
for case_name in "${cases[@]}"; do
  for restitution in constant calibrated; do
    echo "== $case_name, $restitution restitution"
    "$root/build/release/src/pdamp" compare --scenario "$root/data/scenarios/$case_name.ini" \
      --set "hard.restitution=$restitution" --threads "$threads" --db "$db"
  done
done
