#!/usr/bin/env bash
# Integration test of studies on Slurm (issue 26) on a real single-node Slurm
# (tools/slurm-local.sh, MaxArraySize 5): submits an 8-point study of data/scenarios/small.ini
# (both models from one bed per point) as two job arrays (points 1-5 and 6-8) of at most 2
# tasks at once each, cancels one task mid-run
# (scancel: SIGTERM, the task stores its point as interrupted) and kills another (SIGKILL to
# its processes, as a node that fails would: its shard is left unfinished), collects, resubmits the two points with
# --resume, collects again, and checks the store bit for bit against the same study run
# locally with `pdamp study run`: each point's metrics, the models' agreement, and every
# column but ids and times of the latest runs, their samples and cycles (doubles compared as
# their IEEE-754 bits). Prints the time from submit to collected.
# Uses the local Slurm if `tools/slurm-local.sh start` started it, and leaves it running;
# otherwise starts one, stops it at the end and checks nothing of it is left.
# Needs root (or sudo), the packages tools/slurm-local.sh installs, and the ci build
# (tools/build.sh ci), or PDAMP=/path/to/pdamp. Fails with a message if anything is missing.
# Usage: tools/slurm-study-test.sh
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=tools/slurm-lib.sh
source "$repo/tools/slurm-lib.sh"
local_slurm=$repo/tools/slurm-local.sh
pdamp=${PDAMP:-$repo/build/ci/src/pdamp}
queue_timeout_s=300
cancelled_point=2 # long points (run.duration_s = 1.2): SIGTERM mid-run
cancelled_task=1  # its index in the first array, which runs points 1 to 5
killed_point=4    # SIGKILL mid-run
killed_task=3
own_cluster=1     # 0: a local Slurm started before, left running
jobs=()           # the jobs submitted, cancelled if the test fails on a cluster it leaves running

fail() {
  echo "slurm-study-test: FAIL: $*" >&2
  exit 1
}
say() { echo "slurm-study-test: $*"; }

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

# 8 points: four host dampings, each for a short and a long run.
write_study() {
  cat >"$work/study.ini" <<EOF
[study]
name = slurm-test
scenario = $repo/data/scenarios/small.ini
models = both

[sweep]
host.damping_N_s_m = 0.1, 0.2, 0.3, 0.4
run.duration_s = 0.15, 1.2
EOF
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

# The log of task $2 of job $1 shows it running the soft model, past settling.
task_computing() {
  grep -q "soft" "$work/runs.sqlite.shards/study-1/logs/${1}_$2.log" 2>/dev/null
}

# Each row of a query on the latest runs of a point, as text with doubles as their bits, in
# both stores; prints the rows in either store that the other lacks, and how many rows
# the Slurm store has.
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

compare_point_tables() {
  local metrics="dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J, psi_peak, psi_peak_gamma, final_amplitude_m, cycles, energy_balance_rel_err"
  local agreement="envelope_max_rel_diff, envelope_rms_rel_diff, psi_mean_abs_diff, dissipated_rel_diff, small_amplitude_freq_soft_hz, small_amplitude_freq_hard_hz"
  local differing
  differing=$(($(sqlite3 "$work/runs.sqlite" "ATTACH '$work/reference.sqlite' AS ref;
    SELECT count(*) FROM (SELECT point, model, $metrics FROM main.study_point_metrics
      EXCEPT SELECT point, model, $metrics FROM ref.study_point_metrics);
    SELECT count(*) FROM (SELECT point, model, $metrics FROM ref.study_point_metrics
      EXCEPT SELECT point, model, $metrics FROM main.study_point_metrics);
    SELECT count(*) FROM (SELECT point, $agreement FROM main.study_agreement
      EXCEPT SELECT point, $agreement FROM ref.study_agreement);
    SELECT abs(16 - count(*)) FROM main.study_point_metrics; SELECT abs(8 - count(*)) FROM main.study_agreement;" |
    paste -sd+)))
  ((differing == 0)) || fail "$differing point metrics or agreements differ between the Slurm study and the local one"
  say "point metrics (16) and the models' agreement (8): the same"
}

compare_stores() {
  compare_point_tables
  compare_rows "runs" runs "scenario_name, scenario_text, seed, n_particles, duration_s, dt_s, pdamp_version, status, message, sim_time_s, initial_energy_J, energy_balance_rel_err, solid_fraction"
  compare_rows "samples" samples "t_s, host_z_m, host_v_m_s, particle_translational_J, particle_rotational_J, host_kinetic_J, spring_potential_J, gravitational_potential_J, contact_elastic_J, excitation_work_J, dissipated_impact_J, dissipated_friction_J, dissipated_viscous_J, energy_balance_rel_err, time_steps, collisions, contacts, riding_spheres"
  compare_rows "cycles" cycles "cycle, t_start_s, t_end_s, amplitude_m, freq_hz, gamma, psi, psi_impact, psi_friction, psi_viscous, max_host_kinetic_J"
  local beds
  beds=$(sqlite3 "$work/runs.sqlite" "SELECT count(*) FROM initial_states")
  [ "$beds" = 1 ] || fail "$beds settled beds in the Slurm study's store; the shards' identical beds should be one"
}

submit_and_cancel() {
  local job submitted
  run_pdamp study submit "$work/study.ini" --slurm --max-parallel 2 --time 10 || fail "study submit failed"
  expect_output "8 points submitted as 2 job arrays"
  mapfile -t submitted < <(submitted_jobs)
  ((${#submitted[@]} == 2)) || fail "expected two job ids in submit's output"
  jobs+=("${submitted[@]}")
  job=${submitted[0]}
  expect_output "job $job (array 0-4: points 1-5)"
  expect_output "job ${submitted[1]} (array 0-2: points 6-8)"
  grep -qx "#SBATCH --array=0-4%2" "$work/runs.sqlite.shards/study-1/submit-1.sh" || fail "the first job script's array is not 0-4%2"
  grep -qx "#SBATCH --array=0-2%2" "$work/runs.sqlite.shards/study-1/submit-2.sh" || fail "the second job script's array is not 0-2%2"
  wait_for "task $cancelled_task of job $job to compute" "$queue_timeout_s" task_computing "$job" "$cancelled_task"
  scancel "${job}_$cancelled_task"
  say "cancelled task $cancelled_task of job $job (point $cancelled_point) mid-run"
  wait_for "task $killed_task of job $job to compute" "$queue_timeout_s" task_computing "$job" "$killed_task"
  kill_task "$job" "$killed_task"
  say "killed task $killed_task of job $job (point $killed_point) mid-run"
  for job in "${submitted[@]}"; do wait_for "job $job to end" "$queue_timeout_s" job_done "$job"; done
  first_job=${submitted[0]}
}

# SIGKILL to the processes of task $2 of job $1, which Slurm lists by the task's own job id.
# (scancel --signal=KILL cancels as scancel does: SIGTERM first, and the task ends cleanly.)
kill_task() {
  local id pids
  id=$(squeue -h -j "${1}_$2" -o %A)
  [[ "$id" =~ ^[0-9]+$ ]] || fail "squeue does not know task $2 of job $1: '$id'"
  pids=$(scontrol listpids "$id" | awk 'NR > 1 && $3 == "batch" { print $1 }' | paste -sd' ')
  [ -n "$pids" ] || fail "scontrol listpids $id lists no processes of task $2 of job $1"
  # shellcheck disable=SC2086 # one argument per PID
  kill -KILL $pids
}

collect_and_resume() {
  local job
  run_pdamp study status 1 || fail "study status failed"
  expect_output "task $killed_task of job $first_job left an unfinished shard"
  run_pdamp study collect 1 || fail "study collect failed"
  expect_output "6 of 8 points completed;"
  expect_output "collected task $cancelled_task of job $first_job (point $cancelled_point, "
  expect_output "pdamp: point $cancelled_point: interrupted in task $cancelled_task of job $first_job: run "
  expect_output "pdamp: point $killed_point: task $killed_task of job $first_job left an unfinished shard: it was killed while running"
  run_pdamp study submit --resume 1 --slurm --time 10 || fail "study submit --resume failed"
  expect_output "2 points submitted as 1 job array"
  job=$(submitted_jobs)
  jobs+=("$job")
  expect_output "job $job (array 0-1: points $cancelled_point,$killed_point)"
  wait_for "job $job to end" "$queue_timeout_s" job_done "$job"
  run_pdamp study collect 1 || fail "the second study collect failed"
  expect_output "8 of 8 points completed"
  run_pdamp study collect 1 || fail "the third study collect failed"
  expect_output "0 shards collected now"
}

stop_cluster() {
  local folder
  ((own_cluster)) || return 0
  folder=$(dirname "$SLURM_CONF")
  "$local_slurm" stop >/dev/null || fail "tools/slurm-local.sh stop failed"
  [ ! -e "$folder" ] || fail "stop left $folder"
  unset SLURM_CONF
}

main() {
  local started_at=$EPOCHREALTIME submitted_at collected_at
  check_prerequisites
  trap on_exit EXIT
  work=$(mktemp -d /tmp/pdamp-slurm-study.XXXXXX)
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
  say "submit to collected (with the cancel and the resubmission): $(awk "BEGIN { printf \"%.1f\", $collected_at - $submitted_at }") s; whole test $(awk "BEGIN { printf \"%.1f\", $EPOCHREALTIME - $started_at }") s"
  say "passed"
}

main
