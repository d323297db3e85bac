#!/usr/bin/env bash
# Study benchmark: points per hour of `pdamp study run --jobs 2` against `--jobs 1` on a
# sweep of independent points, and the store's bytes per point.
# The sweep: small.ini (100 spheres) on the soft model, 8 host dampings, 0.5 s each, from
# one bed settled beforehand (every round starts from a copy of the store that holds it,
# so settling is not timed). Rounds alternate --jobs 1 and --jobs 2; each prints its
# points per hour, and the end the ratio of each round pair with its median and spread.
# Usage: tools/bench-study.sh [--rounds N] [--points N] [--duration S]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=3
points=8
duration=0.5
while (($#)); do
  case "$1" in
    --rounds) rounds=$2; shift ;;
    --points) points=$2; shift ;;
    --duration) duration=$2; shift ;;
    *) echo "usage: tools/bench-study.sh [--rounds N] [--points N] [--duration S]" >&2; exit 2 ;;
  esac
  shift
done
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
pdamp="$root/build/release/src/pdamp"
work="$root/build/bench/study"
rm -rf "$work"
mkdir -p "$work"

cat > "$work/sweep.ini" <<INI
[study]
name = bench
scenario = $root/data/scenarios/small.ini
models = soft

[sweep]
host.damping_N_s_m = 0.05:0.4:$points
run.duration_s = $duration
INI
# The bed, settled once (a run of 1 ms stores it).
"$pdamp" run --scenario "$root/data/scenarios/small.ini" --model soft --duration 0.001 --db "$work/bed.sqlite" >/dev/null
bytes() { sqlite3 "$1" "SELECT (SELECT page_count FROM pragma_page_count) - (SELECT freelist_count FROM pragma_freelist_count)" |
  awk -v size="$(sqlite3 "$1" 'PRAGMA page_size')" '{ print $1 * size }'; }
bed_bytes=$(bytes "$work/bed.sqlite")

printf '%-6s %5s %9s %14s\n' round jobs wall_s points_per_hour
declare -A rate
for ((r = 1; r <= rounds; ++r)); do
  for jobs in 1 2; do
    db="$work/round$r-jobs$jobs.sqlite"
    cp "$work/bed.sqlite" "$db"
    start=$(date +%s.%N)
    "$pdamp" study run "$work/sweep.ini" --db "$db" --jobs "$jobs" --threads 1 >/dev/null 2>"$db.log"
    end=$(date +%s.%N)
    rate[$r,$jobs]=$(awk -v n="$points" -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", n * 3600 / (b - a) }')
    printf '%-6s %5s %9.2f %14s\n' "$r" "$jobs" "$(awk -v a="$start" -v b="$end" 'BEGIN { print b - a }')" "${rate[$r,$jobs]}"
  done
done
ratios=$(for ((r = 1; r <= rounds; ++r)); do awk -v a="${rate[$r,2]}" -v b="${rate[$r,1]}" 'BEGIN { printf "%.3f\n", a / b }'; done | sort -n)
echo "jobs 2 / jobs 1, each round: $(echo $ratios)"
echo "median $(echo "$ratios" | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'), spread $(echo "$ratios" | head -1) to $(echo "$ratios" | tail -1)"
db="$work/round1-jobs1.sqlite"
echo "store: $(awk -v all="$(bytes "$db")" -v bed="$bed_bytes" -v n="$points" 'BEGIN { printf "%.0f", (all - bed) / n }') bytes per point" \
  "($(sqlite3 "$db" "SELECT count(*) FROM samples s JOIN study_point_runs USING (run_id)") samples," \
  "$(sqlite3 "$db" "SELECT count(*) FROM cycles c JOIN study_point_runs USING (run_id)") cycles in $points points)"
