#!/usr/bin/env bash
# Integration test of [frf] studies on a real single-node Slurm (issues 26 and 28;
# tools/slurm-local.sh): a study of data/scenarios/small.ini with 60 spheres, soft model
# (whose cost per cycle is steady: the hard model's riding bed below Gamma = 1 takes
# milliseconds), whose points all run to their cap of 60 cycles (an amplitude tolerance no
# cycle meets), so each takes seconds: two start = predict curves (0.01 and 0.02 N at 15,
# 17, 19 Hz, a task each) and two start = bed points (0.01 N at 16 and 18 Hz, a task
# each). The first curve's task is cancelled (scancel: SIGTERM) once it is a fifth into its
# second point, which it stores as interrupted with a checkpoint; collect, submit --resume
# (the curve from point 2, which needs point 1's final state and metrics and its own
# interrupted run, copied into the folder's study), collect, and the store is checked bit
# for bit against the same study run locally with `pdamp study run`: every point's metrics
# and the latest runs' rows and samples (an [frf] point's run records no cycles). The
# resubmitted task must continue point 2 from its checkpoint (its log has no warning that
# it ran it again from its start). Prints the time from submit to collected.
# Uses the local Slurm if `tools/slurm-local.sh start` started it, and leaves it running;
# otherwise starts one, stops it at the end and checks nothing of it is left.
# Needs root (or sudo), the packages tools/slurm-local.sh installs, and the ci build
# (tools/build.sh ci), or PDAMP=/path/to/pdamp. Fails with a message if anything is missing.
# Usage: tools/slurm-frf-test.sh
set -euo pipefail

test_name=slurm-frf-test
# shellcheck source=tools/slurm-test-lib.sh
source "$(dirname "$0")/slurm-test-lib.sh"
cancelled_point=2 # the first curve's second point: SIGTERM mid-point
cancelled_task=0  # the first curve's task
job=              # the first job's id

write_study() {
  local keys="mode = force
host.z0_m = 0
particles.count = 60
amplitude_tolerance = 1e-12
max_cycles = 60"
  cat >"$work/study.ini" <<EOF
[study]
name = slurm-frf-test
scenario = $repo/data/scenarios/small.ini
models = soft

[frf]
$keys
levels = 0.01, 0.02
frequencies = 15, 17, 19
start = predict

[frf.bed]
$keys
levels = 0.01
frequencies = 16, 18
start = bed
EOF
}

# The log of task $2 of job $1 shows its point $3 a fifth done.
point_under_way() {
  grep -q "^pdamp: point $3: soft [2-9]0 %" "$(task_log "$1" "$2")" 2>/dev/null
}

submit_and_cancel() {
  run_pdamp study submit "$work/study.ini" --slurm --max-parallel 2 --time 10 --checkpoint-every 1 ||
    fail "study submit failed"
  expect_output "4 curves (each from its first point to run) submitted as 1 job array"
  job=$(submitted_jobs)
  jobs+=("$job")
  expect_output "job $job (array 0-3: points 1,4,7-8)"
  grep -q -- "--checkpoint-every '1'" "$work/runs.sqlite.shards/study-1/submit-1.sh" ||
    fail "the job script does not pass --checkpoint-every '1' to the tasks"
  wait_for "task $cancelled_task of job $job to be in point $cancelled_point" "$queue_timeout_s" \
    point_under_way "$job" "$cancelled_task" "$cancelled_point"
  scancel "${job}_$cancelled_task"
  say "cancelled task $cancelled_task of job $job in point $cancelled_point"
  wait_for "job $job to end" "$queue_timeout_s" job_done "$job"
}

collect_and_resume() {
  local resumed
  run_pdamp study collect 1 || fail "study collect failed"
  expect_output "6 of 8 points completed;"
  expect_output "pdamp: point $cancelled_point: interrupted in task $cancelled_task of job $job: run "
  run_pdamp study submit --resume 1 --slurm --time 10 --checkpoint-every 1 || fail "study submit --resume failed"
  expect_output "1 curves (each from its first point to run) submitted as 1 job array"
  resumed=$(submitted_jobs)
  jobs+=("$resumed")
  expect_output "job $resumed (array 0-0: points $cancelled_point)"
  wait_for "job $resumed to end" "$queue_timeout_s" job_done "$resumed"
  grep -q "^pdamp: point 3: " "$(task_log "$resumed" 0)" || fail "the resubmitted task did not go on to point 3"
  if grep "warning" "$(task_log "$resumed" 0)"; then
    fail "the resubmitted task did not continue point $cancelled_point from its checkpoint (above)"
  fi
  run_pdamp study collect 1 || fail "the second study collect failed"
  expect_output "8 of 8 points completed"
}

compare_stores() {
  local metrics="settled, cycles_to_steady, cycles_run, measured_cycles, amplitude_m, amplitude_spread_m, phase_rad, normalised_amplitude, gamma, impact_J_per_cycle, friction_J_per_cycle, viscous_J_per_cycle, loss_factor, apparent_mass_kg, equivalent_damping_N_s_m, particle_mass_kg"
  local differing
  differing=$(($(sqlite3 "$work/runs.sqlite" "ATTACH '$work/reference.sqlite' AS ref;
    SELECT count(*) FROM (SELECT point, $metrics FROM main.study_frf_metrics
      EXCEPT SELECT point, $metrics FROM ref.study_frf_metrics);
    SELECT count(*) FROM (SELECT point, $metrics FROM ref.study_frf_metrics
      EXCEPT SELECT point, $metrics FROM main.study_frf_metrics);
    SELECT abs(8 - count(*)) FROM main.study_frf_metrics;
    SELECT count(*) FROM main.study_frf_metrics WHERE settled OR cycles_run <> 60;" | paste -sd+)))
  ((differing == 0)) || fail "$differing point metrics differ between the Slurm study and the local one, or a point did not run to its cap"
  say "point metrics (8, each at its cap of 60 cycles): the same"
  compare_runs
}

run_slurm_test
