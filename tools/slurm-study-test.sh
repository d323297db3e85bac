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

test_name=slurm-study-test
# shellcheck source=tools/slurm-test-lib.sh
source "$(dirname "$0")/slurm-test-lib.sh"
cancelled_point=2 # long points (run.duration_s = 1.2): SIGTERM mid-run
cancelled_task=1  # its index in the first array, which runs points 1 to 5
killed_point=4    # SIGKILL mid-run
killed_task=3

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

# The log of task $2 of job $1 shows it running the soft model, past settling.
task_computing() {
  grep -q "soft" "$(task_log "$1" "$2")" 2>/dev/null
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
  compare_runs
  compare_cycles
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

run_slurm_test
