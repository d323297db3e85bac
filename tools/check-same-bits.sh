#!/usr/bin/env bash
# Whether two pdamp binaries give the same bits: runs each on the same cases, from the same
# settled bed, and compares what they stored. Every sample column and every cycle column
# (compared as numbers, row by row in time order: a double differs if any bit does, but
# for the sign of a zero), the run's status, simulated time, initial energy and balance
# error, and the engine's statistics (all but peak_memory_kB, which is the process's).
# Builds nothing.
#
# Usage: tools/check-same-bits.sh [--beds STORE] [--keep DIR] OLD_PDAMP NEW_PDAMP [MODEL CASE...]
#   MODEL   soft or hard (pdamp run --model)
#   CASE    a scenario file, or a name in data/scenarios, with an optional @DURATION_S:
#           table1  table2@0.05  data/scenarios/table4_f100.ini@0.2
#           Without MODEL and CASE: the refactoring check, small and table1@0.05 soft,
#           small and table1@1.5 hard.
#   --beds STORE  a store that holds the cases' settled beds; it is copied, never written.
#           Without it the old binary settles each case's bed once (the soft engine;
#           minutes for Table 1) and every later run of the case starts from it.
#   --keep DIR    keep the stores (DIR/CASE/old.sqlite, new.sqlite; default: a temporary
#           folder, removed at the end)
# Prints one line per case (the two runs' wall times for information, not as a benchmark)
# and what differs. Exit 0 if every case gives the same bits, 1 if any differs or a run
# fails, 2 on a usage error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
usage() {
  sed -n '/^# Usage:/,/^# Prints/p' "$0" | sed 's/^# \{0,1\}//' | head -n -1 >&2
  exit 2
}
beds="" keep=""
while [ $# -gt 0 ]; do
  case $1 in
    --beds) [ $# -ge 2 ] || usage; beds=$2; shift 2 ;;
    --keep) [ $# -ge 2 ] || usage; keep=$2; shift 2 ;;
    -h | --help) usage ;;
    -*) echo "tools/check-same-bits.sh: unknown option '$1' (valid: --beds STORE, --keep DIR)" >&2; exit 2 ;;
    *) break ;;
  esac
done
[ $# -eq 2 ] || [ $# -ge 4 ] || usage
old=$1 new=$2
shift 2
# One job per run: MODEL CASE.
jobs=()
if [ $# -eq 0 ]; then
  jobs=("soft small" "soft table1@0.05" "hard small" "hard table1@1.5")
else
  model=$1
  shift
  for case_ in "$@"; do jobs+=("$model $case_"); done
fi
for binary in "$old" "$new"; do
  [ -x "$binary" ] || { echo "tools/check-same-bits.sh: '$binary' is not an executable pdamp" >&2; exit 2; }
done
if [ -n "$beds" ] && [ ! -f "$beds" ]; then
  echo "tools/check-same-bits.sh: --beds '$beds' is no file" >&2
  exit 2
fi
# Every case resolved before anything runs.
models=() scenarios=() durations=() names=()
for job in "${jobs[@]}"; do
  model=${job%% *} case_=${job#* }
  case $model in soft | hard) ;; *) echo "tools/check-same-bits.sh: MODEL '$model' must be soft or hard" >&2; exit 2 ;; esac
  scenario=${case_%@*} duration=""
  [ "$scenario" != "$case_" ] && duration=${case_##*@}
  [ -f "$scenario" ] || scenario="$root/data/scenarios/$scenario.ini"
  if [ ! -f "$scenario" ]; then
    echo "tools/check-same-bits.sh: case '$case_': no scenario file ${case_%@*} nor $scenario" >&2
    exit 2
  fi
  if [ -n "$duration" ] && ! [[ $duration =~ ^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$ ]]; then
    echo "tools/check-same-bits.sh: case '$case_': duration '$duration' is not a number of seconds" >&2
    exit 2
  fi
  models+=("$model") scenarios+=("$scenario") durations+=("$duration")
  name="$(basename "$scenario" .ini)${duration:+@$duration}"
  [ "$#" -eq 0 ] && name="$model-$name"  # the default set runs each case with both models
  names+=("$name")
done
if [ -n "$keep" ]; then
  mkdir -p "$keep"
  work=$keep
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

# Runs binary $1 on case $2 into store $3; prints the run's id.
run_case() {
  local binary=$1 k=$2 store=$3 log
  log="${store%.sqlite}.log"
  local args=(run --scenario "${scenarios[$k]}" --model "${models[$k]}" --db "$store")
  [ -n "${durations[$k]}" ] && args+=(--duration "${durations[$k]}")
  if ! "$binary" "${args[@]}" >"$log" 2>&1; then
    echo "${names[$k]}: $binary failed (exit $?); its output:" >&2
    cat "$log" >&2
    return 1
  fi
  sqlite3 "$store" "SELECT max(run_id) FROM runs"
}

# The columns of table $3 but run_id that stores $1 and $2 both have.
columns() {
  sqlite3 "$2" "ATTACH '$1' AS old; SELECT name FROM pragma_table_info('$3', 'main') WHERE name != 'run_id'
    INTERSECT SELECT name FROM pragma_table_info('$3', 'old')"
}

# The store's schema version.
schema() { sqlite3 "$1" "PRAGMA user_version"; }

# Compares table $1 of run $5 in store $3 (before) with run $6 in store $4 (now), row by
# row in the order of column $2: prints what differs, column by column (the columns both
# have). When the new binary's schema differs, the samples compared are the old run's as
# the new binary migrated them, in its store.
compare_rows() {
  local table=$1 order=$2 store_old=$3 store_new=$4 a=$5 b=$6 per_column="" c
  for c in $(columns "$store_old" "$store_new" "$table"); do
    per_column+="${per_column:+ UNION ALL }SELECT '$c' AS name, sum(NOT (o.$c IS n.$c)) AS rows,
      min(CASE WHEN NOT (o.$c IS n.$c) THEN o.$order END) AS first FROM o JOIN n USING (k)"
  done
  sqlite3 -separator ' ' "$store_new" "ATTACH '$store_old' AS old;
    CREATE TEMP TABLE o AS SELECT row_number() OVER (ORDER BY $order) AS k, * FROM old.$table WHERE run_id = $a;
    CREATE TEMP TABLE n AS SELECT row_number() OVER (ORDER BY $order) AS k, * FROM main.$table WHERE run_id = $b;
    SELECT '$table: ' || (SELECT count(*) FROM o) || ' rows before, ' || (SELECT count(*) FROM n) || ' now'
      WHERE (SELECT count(*) FROM o) != (SELECT count(*) FROM n);
    SELECT '$table: ' || name || ' differs in ' || rows || ' rows, first at $order = ' || first
      FROM ($per_column) WHERE rows > 0;"
}

shared_beds=0
[ -z "$beds" ] && shared_beds=1
failed=0
for k in "${!names[@]}"; do
  dir="$work/${names[$k]}"
  mkdir -p "$dir"
  rm -f "$dir"/*.sqlite*
  if [ -n "$beds" ]; then
    sqlite3 "$beds" ".backup '$dir/old.sqlite'"
  fi
  a=$(run_case "$old" "$k" "$dir/old.sqlite") || { failed=1; continue; }
  if [ "$shared_beds" = 1 ]; then  # the beds settled so far, for the next cases
    beds="$work/beds.sqlite"
    sqlite3 "$dir/old.sqlite" ".backup '$beds'"
  fi
  sqlite3 "$dir/old.sqlite" ".backup '$dir/new.sqlite'"  # with the bed the old run started from
  b=$(run_case "$new" "$k" "$dir/new.sqlite") || { failed=1; continue; }
  differences=$(
    if [ "$(schema "$dir/old.sqlite")" = "$(schema "$dir/new.sqlite")" ]; then
      compare_rows samples t_s "$dir/old.sqlite" "$dir/new.sqlite" "$a" "$b"
    else  # the old run as the new binary migrated it (new.sqlite is a copy of old.sqlite)
      compare_rows samples t_s "$dir/new.sqlite" "$dir/new.sqlite" "$a" "$b" | sed 's/^/(migrated) /'
    fi
    compare_rows cycles cycle "$dir/old.sqlite" "$dir/new.sqlite" "$a" "$b"
    sqlite3 -separator ' ' "$dir/new.sqlite" "ATTACH '$dir/old.sqlite' AS old;
      SELECT 'run: ' || o.status || ' ' || o.sim_time_s || ' s, balance ' || o.energy_balance_rel_err ||
             ', E0 ' || o.initial_energy_J || ' before; ' || n.status || ' ' || n.sim_time_s || ' s, balance ' ||
             n.energy_balance_rel_err || ', E0 ' || n.initial_energy_J || ' now'
      FROM old.runs o, main.runs n WHERE o.run_id = $a AND n.run_id = $b AND NOT (o.status IS n.status AND
        o.sim_time_s IS n.sim_time_s AND o.energy_balance_rel_err IS n.energy_balance_rel_err AND
        o.initial_energy_J IS n.initial_energy_J AND o.initial_state_id IS n.initial_state_id);
      SELECT 'statistic ' || name || ': ' || group_concat(side || ' ' || value, ', ') FROM (
        SELECT 'before' AS side, name, value FROM (SELECT name, value FROM old.run_statistics WHERE run_id = $a
          EXCEPT SELECT name, value FROM main.run_statistics WHERE run_id = $b)
        UNION ALL
        SELECT 'now', name, value FROM (SELECT name, value FROM main.run_statistics WHERE run_id = $b
          EXCEPT SELECT name, value FROM old.run_statistics WHERE run_id = $a))
      WHERE name != 'peak_memory_kB' GROUP BY name;"
  )
  summary=$(sqlite3 -separator ' ' "$dir/new.sqlite" "ATTACH '$dir/old.sqlite' AS old;
    SELECT (SELECT count(*) FROM main.samples WHERE run_id = $b) || ' samples, ' ||
           (SELECT count(*) FROM main.cycles WHERE run_id = $b) || ' cycles, wall ' ||
           round((SELECT wall_time_s FROM old.runs WHERE run_id = $a), 2) || ' s before, ' ||
           round((SELECT wall_time_s FROM main.runs WHERE run_id = $b), 2) || ' s now'")
  if [ -z "$differences" ]; then
    echo "${names[$k]}: same bits ($summary)"
  else
    failed=1
    echo "${names[$k]}: DIFFERENT ($summary)"
    echo "$differences" | sed 's/^/  /'
  fi
done
exit "$failed"
