#!/usr/bin/env bash
# Soft-engine benchmark: throughput in particle-steps per second (particles x steps / wall
# seconds of the run itself, settling excluded) and memory per particle, for
#   - the paper's Table 2 free decay (data/scenarios/table2.ini),
#   - the same bed shaken at 5 mm, 30.8 Hz (data/scenarios/bench/table2_shaken.ini), the
#     case run beside LIGGGHTS (tools/bench/liggghts), periods 2-4 after one warm-up period,
#   - that shaken bed scaled to ~5,000 and ~20,000 spheres (wider cavity, same bed height).
# Usage: tools/bench-soft.sh [--full] [--threads "1 2"]
#   --full     the whole 1.5 s of Table 2 (default: its first 0.1 s)
# Settled beds are kept in build/bench/bench.sqlite: each is settled once, on all cores
# (the bed is the same bits on any number of threads), before any run is timed.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
table2_duration=0.1
thread_counts="1"
while (($#)); do
  case "$1" in
    --full) table2_duration=1.5 ;;
    --threads) thread_counts=$2; shift ;;
    *) echo "usage: tools/bench-soft.sh [--full] [--threads \"1 2\"]" >&2; exit 2 ;;
  esac
  shift
done
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
source "$root/tools/bench-lib.sh"

baseline=$(run --scenario "$root/data/scenarios/table2.ini" --model soft --set particles.count=0 --duration 0.01)
baseline_kB=$(stat "$baseline" peak_memory_kB)

printf '%-34s %8s %7s %12s %10s %16s %12s\n' case particles threads steps wall_s particle_steps/s bytes/particle
report() {  # name particles threads steps wall_s peak_kB
  awk -v name="$1" -v n="$2" -v t="$3" -v steps="$4" -v wall="$5" -v kB="$6" -v base="$baseline_kB" 'BEGIN {
    printf "%-34s %8d %7d %12d %10.3f %16.3e %12.0f\n", name, n, t, steps, wall, n * steps / wall, (kB - base) * 1024 / n }'
}

# The shaken bed at each size: particles, cavity diameter.
sizes=("1246 0.010" "4984 0.020" "19936 0.040")
run --scenario "$root/data/scenarios/table2.ini" --model soft --duration 0.0005 >/dev/null
for size in "${sizes[@]}"; do shaken $size --duration 0.0005 >/dev/null; done

for threads in $thread_counts; do
  id=$(pinned_if_one_thread "$threads" run --scenario "$root/data/scenarios/table2.ini" --model soft \
    --threads "$threads" --duration "$table2_duration")
  report "table2 free decay ${table2_duration} s" 1246 "$threads" "$(stat "$id" steps)" "$(wall "$id")" "$(stat "$id" peak_memory_kB)"

  for size in "${sizes[@]}"; do
    set -- $size
    read -r steps seconds peak_kB < <(shaken_periods_2_to_4 "$1" "$2" "$threads")
    report "shaken 5 mm 30.8 Hz, periods 2-4" "$1" "$threads" "$steps" "$seconds" "$peak_kB"
  done
done
