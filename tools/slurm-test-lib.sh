# shellcheck shell=bash
# Shared by the tests of studies on a real local Slurm (tools/slurm-study-test.sh,
# tools/slurm-frf-test.sh; sourced): prerequisites, the cluster (tools/slurm-local.sh: used
# if started before and left running, else started and stopped), pdamp with its output,
# and the bit-for-bit comparison of the Slurm study's store with the local one. The test
# sets `test_name` before sourcing, and `work` (its folder, holding runs.sqlite and
# reference.sqlite) before starting the cluster.

: "${test_name:?set test_name before sourcing tools/slurm-test-lib.sh}"
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=tools/slurm-lib.sh
source "$repo/tools/slurm-lib.sh"
local_slurm=$repo/tools/slurm-local.sh
pdamp=${PDAMP:-$repo/build/ci/src/pdamp}
# shellcheck disable=SC2034 # the tests' waits for the queue
queue_timeout_s=300
own_cluster=1 # 0: a local Slurm started before, left running
jobs=()       # the jobs submitted, cancelled if the test fails on a cluster it leaves running

fail() {
  echo "$test_name: FAIL: $*" >&2
  exit 1
}
say() { echo "$test_name: $*"; }

on_exit() {
  local status=$?
  if ((status != 0)) && [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
    squeue -r -t all >&2 || true
    [ -z "${work:-}" ] || tail -n 5 "$work"/runs.sqlite.shards/study-1/logs/*.log >&2 || true
    if ((own_cluster)); then
      "$local_slurm" stop >&2 || true
    elif ((${#jobs[@]})); then
      scancel "${jobs[@]}" || true
    fi
  fi
  [ -z "${work:-}" ] || rm -rf "$work"
}

check_prerequisites() {
  [ -x "$pdamp" ] || fail "no pdamp at $pdamp: build it (tools/build.sh ci) or give PDAMP=/path/to/pdamp"
  command -v sqlite3 >/dev/null || "$repo/tools/setup.sh" sqlite3 >/dev/null ||
    fail "sqlite3 is missing and tools/setup.sh sqlite3 failed"
  [ "$(sqlite3 :memory: "SELECT hex(ieee754_to_blob(-0.0))")" = 8000000000000000 ] ||
    fail "this sqlite3 lacks ieee754_to_blob, which the bit-for-bit comparison needs"
  local status=0 output
  output=$("$local_slurm" status 2>&1) || status=$?
  case $status in
    0) own_cluster=0 ;;
    3) ;;
    *) fail "tools/slurm-local.sh status: $(tail -n 1 <<<"$output")" ;; # partly running, or no root
  esac
}

# Starts the local Slurm, or finds the one running; either prints its SLURM_CONF line.
start_cluster() {
  local output command=start
  ((own_cluster)) || command=status
  output=$("$local_slurm" "$command") || fail "tools/slurm-local.sh $command failed"
  eval "$(grep '^export SLURM_CONF=' <<<"$output")"
  [ -f "${SLURM_CONF:-}" ] || fail "$command printed no usable SLURM_CONF line: $output"
  ((own_cluster)) || say "using the local Slurm already running ($SLURM_CONF); it is left running"
}

stop_cluster() {
  local folder
  ((own_cluster)) || return 0
  folder=$(dirname "$SLURM_CONF")
  "$local_slurm" stop >/dev/null || fail "tools/slurm-local.sh stop failed"
  [ ! -e "$folder" ] || fail "stop left $folder"
  unset SLURM_CONF
}

# Runs pdamp; the output also goes to the test's output.
run_pdamp() {
  "$pdamp" "$@" --db "$work/runs.sqlite" 2>&1 | tee "$work/last.out"
  return "${PIPESTATUS[0]}"
}

expect_output() {
  grep -qF -- "$1" "$work/last.out" || fail "expected '$1' in the output above"
}

# The job ids in submit's output, a line each: "  job J (array 0-N: points ...), script ...".
submitted_jobs() {
  sed -n 's/^  job \([0-9]*\) (array .*/\1/p' "$work/last.out"
}

job_done() {
  [ -z "$(squeue -h -j "$1" -t PENDING,RUNNING,CONFIGURING,COMPLETING,SUSPENDED 2>/dev/null)" ]
}

# The log of task $2 of job $1.
task_log() {
  echo "$work/runs.sqlite.shards/study-1/logs/${1}_$2.log"
}

# Each row of a query on the latest runs of a point, as text with doubles as their bits, in
# both stores; fails naming how many rows either store has that the other lacks, else says
# how many rows the Slurm store has.
compare_rows() {
  local what=$1 table=$2 columns=$3 expression="" column
  for column in ${columns//,/ }; do
    expression+="${expression:+, }CASE typeof(x.$column) WHEN 'real' THEN hex(ieee754_to_blob(x.$column)) ELSE quote(x.$column) END"
  done
  local latest="SELECT l.point, l.model, l.run_id FROM DB.study_point_runs l JOIN DB.study_points p USING (study_id, point, attempt)"
  local rows="SELECT r.point, r.model, $expression FROM ($latest) r JOIN DB.$table x USING (run_id)"
  local ours=${rows//DB/main} theirs=${rows//DB/ref}
  local differing count
  differing=$(($(sqlite3 "$work/runs.sqlite" "ATTACH '$work/reference.sqlite' AS ref;
    SELECT count(*) FROM (SELECT * FROM ($ours) EXCEPT SELECT * FROM ($theirs));
    SELECT count(*) FROM (SELECT * FROM ($theirs) EXCEPT SELECT * FROM ($ours));" | paste -sd+)))
  count=$(sqlite3 "$work/runs.sqlite" "SELECT count(*) FROM ($ours)")
  ((count > 0)) || fail "no $what to compare"
  ((differing == 0)) || fail "$differing $what differ between the Slurm study and the local one"
  say "$what: $count rows, the same bits"
}

# The latest runs' rows (all but ids and times) and samples.
compare_runs() {
  compare_rows "runs" runs "scenario_name, scenario_text, seed, n_particles, duration_s, dt_s, pdamp_version, status, message, sim_time_s, initial_energy_J, energy_balance_rel_err, solid_fraction"
  compare_rows "samples" samples "t_s, host_z_m, host_v_m_s, particle_translational_J, particle_rotational_J, host_kinetic_J, spring_potential_J, gravitational_potential_J, contact_elastic_J, excitation_work_J, dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J, energy_balance_rel_err, time_steps, collisions, contacts, riding_spheres"
}

# The latest runs' cycles (a free decay's: an [frf] point's runs record none).
compare_cycles() {
  compare_rows "cycles" cycles "cycle, t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi, psi_impact, psi_friction, psi_viscous, max_host_kinetic_J"
}

# "N.N" seconds since $1 (an $EPOCHREALTIME).
seconds_since() {
  awk "BEGIN { printf \"%.1f\", $EPOCHREALTIME - $1 }"
}

# The test's course: the local Slurm, the study on it (the test's write_study,
# submit_and_cancel and collect_and_resume), the same study run locally, the test's
# compare_stores; prints the times and "passed".
run_slurm_test() {
  local started_at=$EPOCHREALTIME submitted_at collected_at
  check_prerequisites
  trap on_exit EXIT
  work=$(mktemp -d "/tmp/pdamp-$test_name.XXXXXX")
  chmod 755 "$work"
  write_study
  start_cluster
  submitted_at=$EPOCHREALTIME
  submit_and_cancel
  collect_and_resume
  collected_at=$EPOCHREALTIME
  stop_cluster
  "$pdamp" study run "$work/study.ini" --db "$work/reference.sqlite" --jobs 2 >/dev/null 2>"$work/reference.err" ||
    fail "the local study run failed: $(cat "$work/reference.err")"
  compare_stores
  say "submit to collected (with the cancel and the resubmission): $(awk "BEGIN { printf \"%.1f\", $collected_at - $submitted_at }") s; whole test $(seconds_since "$started_at") s"
  say "passed"
}
