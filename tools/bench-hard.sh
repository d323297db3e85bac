#!/usr/bin/env bash
# Hard-engine benchmark (docs/benchmarks.md, "Hard engine"):
#   1. pdamp_bench: elastic frictionless spheres, no gravity, closed cylinder, solid
#      fraction 0.3, N = 1,000 / 10,000 / 100,000 — collisions per second on one core,
#      memory per sphere, energy error; with a fixed host, then with a free host, where
#      every cap collision is an impulse on the host (what those cost as N grows).
#   2. The paper's Table 1 damper for 1.5 s on the hard model (wall time of the run
#      itself; the shared settled bed is made once and kept in build/bench/bench.sqlite).
#   3. With --against-soft: then Table 1 soft (one thread) and hard again, on the same core,
#      and the ratio of the soft run's wall time to each hard one's.
#   4. With --counts, instead of all that: what one collision of the gas (fixed host) costs
#      in operations as N grows, under cachegrind with this machine's L1d and L2 sizes —
#      instructions, L1 and L2 misses per collision, from the difference of a 2·10⁵- and a
#      4·10⁵-collision run, so that setting up and warming up cancel. Deterministic (no
#      timing); a few minutes.
# Usage: tools/bench-hard.sh [--quick] [--against-soft] | --counts
#   (--quick: N = 1,000 and 10,000, Table 1 for 0.3 s)
# Every timed run is on one core (PDAMP_BENCH_CORE, see tools/bench-lib.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sizes="1000 10000 100000"
table1_duration=1.5
against_soft=0
counts=0
for arg in "$@"; do
  case $arg in
    --quick) sizes="1000 10000"; table1_duration=0.3 ;;
    --against-soft) against_soft=1 ;;
    --counts) counts=1 ;;
    *) echo "tools/bench-hard.sh: unknown option '$arg' (valid: --quick, --against-soft, --counts)" >&2; exit 2 ;;
  esac
done
if [ "$counts" = 1 ] && [ "$against_soft" = 1 ]; then
  echo "tools/bench-hard.sh: --counts runs no timed case, so --against-soft has nothing to add; give one of them" >&2
  exit 2
fi
bench="$root/build/release/tools/bench/pdamp_bench"
if [ "$counts" = 1 ]; then
  "$root/tools/setup.sh" valgrind
  "$root/tools/build.sh" release >/dev/null
  # A cache parameter as getconf reads it, or the development machine's where it reads none.
  cache() { local v; v=$(getconf "$1" 2>/dev/null || true); [[ $v =~ ^[1-9][0-9]*$ ]] && echo "$v" || echo "$2"; }
  caches=(--D1="$(cache LEVEL1_DCACHE_SIZE 49152),$(cache LEVEL1_DCACHE_ASSOC 12),64"
          --LL="$(cache LEVEL2_CACHE_SIZE 1048576),$(cache LEVEL2_CACHE_ASSOC 8),64")
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  echo "per collision (cachegrind ${caches[*]}): instructions, L1d misses, L2 misses"
  for n in $sizes; do
    for c in 200000 400000; do
      if ! valgrind --tool=cachegrind --cache-sim=yes "${caches[@]}" --cachegrind-out-file="$work/cg.$c" \
        "$bench" --particles "$n" --host fixed --collisions "$c" >"$work/out.$c" 2>"$work/err.$c"; then
        echo "tools/bench-hard.sh --counts: cachegrind failed at N = $n, $c collisions:" >&2
        cat "$work/err.$c" >&2
        exit 1
      fi
    done
    # summary: Ir I1mr ILmr Dr D1mr DLmr Dw D1mw DLmw
    awk -v n="$n" '
      FNR == 1 { file++ }
      /^summary:/ { for (k = 2; k <= NF; k++) s[file, k] = $k }
      /collisions/ { for (k = 1; k < NF; k++) if ($k == "collisions") c[file] = $(k + 1) }
      END {
        d = (c[4] - c[2])
        printf "N %7d  instructions %6.0f  L1d misses %5.1f  L2 misses %5.1f\n", n,
          (s[3, 2] - s[1, 2]) / d, (s[3, 6] + s[3, 9] - s[1, 6] - s[1, 9]) / d,
          (s[3, 7] + s[3, 10] - s[1, 7] - s[1, 10]) / d
      }' "$work/cg.200000" "$work/out.200000" "$work/cg.400000" "$work/out.400000"
  done
  exit 0
fi
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
source "$root/tools/bench-lib.sh"
for host in fixed free; do
  for n in $sizes; do
    on_bench_core "$bench" --particles "$n" --host "$host"
  done
done
id=$(pinned_if_one_thread 1 run --scenario "$root/data/scenarios/table1.ini" --model hard --duration "$table1_duration")
sqlite3 "$db" "SELECT 'table1 hard ' || duration_s || ' s: wall ' || round(wall_time_s, 2) || ' s, balance error ' ||
  energy_balance_rel_err FROM runs WHERE run_id = $id"
sqlite3 "$db" "SELECT name || ' ' || value FROM run_statistics WHERE run_id = $id AND name LIKE 'events_%'"
if [ "$against_soft" = 1 ]; then
  # The hard run above comes first; then soft, and hard again.
  table1() { pinned_if_one_thread 1 run --scenario "$root/data/scenarios/table1.ini" --duration "$table1_duration" "$@"; }
  soft=$(table1 --model soft --threads 1)
  hard_after=$(table1 --model hard)
  awk -v d="$table1_duration" -v a="$(wall "$id")" -v s="$(wall "$soft")" -v b="$(wall "$hard_after")" \
    'BEGIN { printf "table1 %s s on one core: hard %.2f s, soft %.2f s, hard %.2f s; soft/hard %.1f and %.1f\n", d, a, s, b, s / a, s / b }'
fi
