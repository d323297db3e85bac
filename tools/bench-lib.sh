# Shared by the benchmark scripts (sourced, with $root set): pdamp runs stored in
# build/bench/bench.sqlite, and the soft engine's throughput on the shaken Table 2 bed
# (data/scenarios/bench/table2_shaken.ini), the case run beside LIGGGHTS.
pdamp="$root/build/release/src/pdamp"
mkdir -p "$root/build/bench"
db="$root/build/bench/bench.sqlite"
period=$(awk 'BEGIN { printf "%.10f", 1 / 30.8 }')

# Runs pdamp quietly and prints "run_id".
run() { "$pdamp" run --db "$db" "$@" 2>/dev/null | sed -n 's/^run \([0-9]*\):.*/\1/p'; }
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
  warmup=$(shaken "$1" "$2" --threads "$3" --duration "$period")
  full=$(shaken "$1" "$2" --threads "$3" --duration "$(awk -v p="$period" 'BEGIN { printf "%.10f", 4 * p }')")
  echo "$(($(stat "$full" steps) - $(stat "$warmup" steps))) $(awk -v a="$(wall "$full")" -v b="$(wall "$warmup")" 'BEGIN { print a - b }') $(stat "$full" peak_memory_kB)"
}
