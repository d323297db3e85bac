# Shared by the benchmark scripts (sourced, with $root set): pdamp runs stored in
# build/bench/bench.sqlite, and the soft engine's throughput on the shaken Table 2 bed
# (data/scenarios/bench/table2_shaken.ini), the case run beside LIGGGHTS.
pdamp="$root/build/release/src/pdamp"
mkdir -p "$root/build/bench"
db="$root/build/bench/bench.sqlite"
period=$(awk 'BEGIN { printf "%.10f", 1 / 30.8 }')

# Timed runs on one thread go to one core: on a shared virtual machine the cores' speeds
# can differ by tens of per cent, and which one is slow changes within minutes (on the
# development machine one core ran the hard gas at 1.2e6 collisions/s and the other at
# 1.65e6, then the other way round). A run the scheduler moves between them measures a
# mix; runs one after the other on one core compare. PDAMP_BENCH_CORE picks the core
# (default: the last one).
bench_core=${PDAMP_BENCH_CORE:-$(($(nproc) - 1))}
if ! [[ $bench_core =~ ^[0-9]+$ ]] || ((bench_core >= $(nproc))); then
  echo "PDAMP_BENCH_CORE='$bench_core': must be a core number from 0 to $(($(nproc) - 1))" >&2
  exit 2
fi
on_bench_core() { taskset -c "$bench_core" "$@"; }
pin=()  # the prefix of pdamp's runs (see pinned_if_one_thread)
# Runs `threads command...` with pdamp's runs in it on the bench core if threads is 1.
pinned_if_one_thread() {
  local threads=$1
  shift
  if [ "$threads" = 1 ]; then local pin=(on_bench_core); fi
  "$@"
}

# Runs pdamp quietly and prints "run_id".
run() { "${pin[@]}" "$pdamp" run --db "$db" "$@" 2>/dev/null | sed -n 's/^run \([0-9]*\):.*/\1/p'; }
stat() { sqlite3 "$db" "SELECT value FROM run_statistics WHERE run_id = $1 AND name = '$2'"; }
wall() { sqlite3 "$db" "SELECT wall_time_s FROM runs WHERE run_id = $1"; }

# The shaken bed: particles, cavity diameter (the same bed height for every size), [pdamp run options].
shaken() {
  local n=$1 diameter=$2
  shift 2
  run --scenario "$root/data/scenarios/bench/table2_shaken.ini" --model soft --set "particles.count=$n" \
    --set "cavity.diameter_m=$diameter" "$@"
}
# Periods 2-4 of the shaken bed after one warm-up period (the difference of a 1- and a
# 4-period run, so that loading the settled bed cancels): prints "steps seconds peak_kB".
# Arguments: particles, cavity diameter, threads.
shaken_periods_2_to_4() {
  local warmup full
  warmup=$(pinned_if_one_thread "$3" shaken "$1" "$2" --threads "$3" --duration "$period")
  full=$(pinned_if_one_thread "$3" shaken "$1" "$2" --threads "$3" \
    --duration "$(awk -v p="$period" 'BEGIN { printf "%.10f", 4 * p }')")
  echo "$(($(stat "$full" steps) - $(stat "$warmup" steps))) $(awk -v a="$(wall "$full")" -v b="$(wall "$warmup")" 'BEGIN { print a - b }') $(stat "$full" peak_memory_kB)"
}

# The pdamp to time: PDAMP_BINARY if set, else the release build, built first. Then a
# fresh store build/bench/$1.sqlite for this benchmark's runs.
pdamp_and_store() {
  if [ -n "${PDAMP_BINARY:-}" ]; then
    pdamp=$PDAMP_BINARY
  else
    "$root/tools/build.sh" release >/dev/null
  fi
  db="$root/build/bench/$1.sqlite"
  rm -f "$db"
}

# "median min max" of the numbers on stdin.
median_min_max() {
  sort -g | awk '{ a[NR] = $1 } END { printf "%.4f %.4f %.4f", NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2, a[1], a[NR] }'
}
