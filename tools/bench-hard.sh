#!/usr/bin/env bash
# Hard-engine benchmark (README, "The hard-sphere engine"):
#   1. pdamp_bench: elastic frictionless spheres, no gravity, closed cylinder, solid
#      fraction 0.3, N = 1,000 / 10,000 / 100,000 — collisions per second on one core,
#      memory per sphere, energy error; with a fixed host, then with a free host, where
#      every cap collision is an impulse on the host (what those cost as N grows).
#   2. The paper's Table 1 damper for 1.5 s on the hard model (wall time of the run
#      itself; the shared settled bed is made once and kept in build/bench/bench.sqlite).
# Usage: tools/bench-hard.sh [--quick]   (--quick: N = 1,000 and 10,000, Table 1 for 0.3 s)
# Every timed run is on one core (PDAMP_BENCH_CORE, see tools/bench-lib.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sizes="1000 10000 100000"
table1_duration=1.5
if [ "${1:-}" = --quick ]; then sizes="1000 10000"; table1_duration=0.3; fi
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
source "$root/tools/bench-lib.sh"
bench="$root/build/release/tools/bench/pdamp_bench"
for host in fixed free; do
  for n in $sizes; do
    on_bench_core "$bench" --particles "$n" --host "$host"
  done
done
id=$(pinned_if_one_thread 1 run --scenario "$root/data/scenarios/table1.ini" --model hard --duration "$table1_duration")
sqlite3 "$db" "SELECT 'table1 hard ' || duration_s || ' s: wall ' || round(wall_time_s, 2) || ' s, balance error ' ||
  energy_balance_rel_err FROM runs WHERE run_id = $id"
sqlite3 "$db" "SELECT name || ' ' || value FROM run_statistics WHERE run_id = $id AND name LIKE 'events_%'"
