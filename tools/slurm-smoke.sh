#!/usr/bin/env bash
# Smoke test of the local Slurm (tools/slurm-local.sh), the skeleton of the studies-on-Slurm test:
# per round it starts the cluster, runs a job array of 4 tasks, at most 2 at once, that each write
# a result file; task 1 runs long and is cancelled mid-run, task 3 is cancelled while pending. It
# checks the results and the task states Slurm reports, times a trivial array, stops the cluster
# and checks that nothing is left.
# Needs root (or sudo) and refuses to run beside a local Slurm that is already running.
# Usage: tools/slurm-smoke.sh [ROUNDS]   (default 1)
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=tools/slurm-lib.sh
source "$repo/tools/slurm-lib.sh"
local_slurm=$repo/tools/slurm-local.sh
rounds=${1:-1}
tasks=4
throttle=2
running_cancelled=1 # sleeps until cancelled
pending_cancelled=3 # waits behind the throttle until cancelled
queue_timeout_s=120

fail() {
  echo "slurm-smoke: FAIL: $*" >&2
  exit 1
}
say() { echo "slurm-smoke: $*"; }
joined() { paste -sd, -; }

# On failure: what the cluster says, then stop it, so that a failed run leaves nothing behind.
on_exit() {
  local status=$?
  ((status == 0)) && return
  if [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
    squeue -r -t all >&2 || true
    tail -n 20 "$(dirname "$SLURM_CONF")"/log/*.{log,out} >&2 || true
    "$local_slurm" stop >&2 || true
  fi
  [ -z "${work:-}" ] || rm -rf "$work"
}

# The array task: the study's point is SLURM_ARRAY_TASK_ID. The result appears by rename, whole
# or not at all, as a shard store will; a missing result means the task did not finish.
write_task_script() {
  cat >"$work/task.sh" <<EOF
#!/bin/bash
set -euo pipefail
id=\$SLURM_ARRAY_TASK_ID
touch "started.\$id"
if [ "\$id" = $running_cancelled ]; then sleep 300; else sleep 1; fi
echo "\$SLURM_ARRAY_JOB_ID \$id \$SLURM_ARRAY_TASK_COUNT" >"result.\$id.part"
mv "result.\$id.part" "result.\$id"
EOF
  chmod +x "$work/task.sh"
}

start_cluster() {
  local output started_at=$SECONDS
  output=$("$local_slurm" start) || fail "tools/slurm-local.sh start failed"
  eval "$(grep '^export SLURM_CONF=' <<<"$output")"
  [ -f "${SLURM_CONF:-}" ] || fail "start printed no usable SLURM_CONF line: $output"
  say "start: $((SECONDS - started_at)) s"
}

# Prints the array's tasks as "TASK_ID STATE" lines, finished ones included (kept for MinJobAge).
task_states() {
  local job=$1
  squeue -h -r -t all -j "$job" -o '%K %T' | sort -n
}

array_done() {
  local job=$1
  [ -z "$(squeue -h -j "$job" -t PENDING,RUNNING,CONFIGURING,COMPLETING,SUSPENDED)" ]
}

running_at_most() {
  local job=$1 limit=$2 running
  running=$(squeue -h -r -j "$job" -t RUNNING | wc -l)
  ((running <= limit)) || fail "$running tasks of job $job run at once; the throttle is $limit"
}

# Waits for the array to end, checking the throttle on the way.
wait_for_array() {
  local job=$1 deadline=$((SECONDS + queue_timeout_s))
  until array_done "$job"; do
    running_at_most "$job" "$throttle"
    ((SECONDS < deadline)) || fail "job $job not done after $queue_timeout_s s: $(task_states "$job")"
    sleep 0.2
  done
}

# The pending task first: cancelling the running one frees its slot. Until then the pending task
# can start only after tasks 0 and 2 have run 1 s each.
cancel_tasks() {
  local job=$1
  wait_for "task $running_cancelled to start" "$queue_timeout_s" test -e "$work/started.$running_cancelled"
  squeue -h -r -j "$job" -t PENDING -o %K | grep -qx "$pending_cancelled" ||
    fail "task $pending_cancelled of job $job is not pending: $(task_states "$job" | joined)"
  scancel "${job}_$pending_cancelled"
  scancel "${job}_$running_cancelled"
}

cancelled() {
  local id=$1
  ((id == running_cancelled || id == pending_cancelled))
}

# Processes still in the work folder after the array ended: a cancelled task that was not killed.
check_no_task_processes() {
  local left
  left=$(find /proc/[0-9]*/cwd -maxdepth 0 \( -lname "$work" -o -lname "$work/*" \) 2>/dev/null || true)
  [ -z "$left" ] || fail "task processes outlived job: $left"
}

# A study finds its missing points this way: the tasks without a result.
check_results() {
  local job=$1 id result missing=()
  for ((id = 0; id < tasks; id++)); do
    result=$(cat "$work/result.$id" 2>/dev/null) || {
      missing+=("$id")
      continue
    }
    ! cancelled "$id" || fail "the cancelled task $id wrote its result"
    [ "$result" = "$job $id $tasks" ] || fail "task $id: result '$result', expected '$job $id $tasks'"
  done
  [ "${missing[*]}" = "$running_cancelled $pending_cancelled" ] || fail "tasks without a result: ${missing[*]}"
  say "tasks without a result: ${missing[*]}"
}

# What Slurm 22.05 reports: the task cancelled while pending leaves no record at all (it never
# left the array's pending record), so only a missing result tells it was not run.
expected_states() {
  local id
  for ((id = 0; id < tasks; id++)); do
    if ((id == running_cancelled)); then
      echo "$id CANCELLED"
    elif ((id != pending_cancelled)); then
      echo "$id COMPLETED"
    fi
  done
}

# The job-completion file is the durable record (squeue forgets after MinJobAge; no slurmdbd, so
# no sacct): one line per task with ArrayTaskId and JobState.
jobcomp_states() {
  local job=$1
  grep "ArrayJobId=$job " "$(dirname "$SLURM_CONF")/log/jobcomp.txt" |
    sed -E 's/.*JobState=([A-Z_]+).*ArrayTaskId=([0-9]+).*/\2 \1/' | sort -n
}

jobcomp_complete() {
  local job=$1
  (($(jobcomp_states "$job" | wc -l) == $(expected_states | wc -l)))
}

check_states() {
  local job=$1 expected
  expected=$(expected_states)
  [ "$(task_states "$job")" = "$expected" ] ||
    fail "squeue states of job $job: $(task_states "$job" | joined), expected $(joined <<<"$expected")"
  wait_for "job $job's completion records" 10 jobcomp_complete "$job"
  [ "$(jobcomp_states "$job")" = "$expected" ] || fail "jobcomp states of job $job: $(jobcomp_states "$job" | joined)"
  say "task states (squeue and jobcomp): $(joined <<<"$expected")"
}

run_cancelled_array() {
  local job
  write_task_script
  job=$(sbatch --parsable --array="0-$((tasks - 1))%$throttle" --chdir="$work" -o "$work/log.%A_%a" \
    -J pdamp-smoke --time=10 "$work/task.sh") || fail "sbatch refused the array"
  cancel_tasks "$job"
  wait_for_array "$job"
  check_no_task_processes
  check_results "$job"
  check_states "$job"
}

time_trivial_array() {
  local job started_at=$EPOCHREALTIME
  job=$(sbatch --parsable --array="0-$((tasks - 1))%$throttle" --chdir="$work" -o /dev/null --wrap=true)
  wait_for_array "$job"
  say "trivial array of $tasks tasks (%$throttle): $(awk "BEGIN { printf \"%.1f\", $EPOCHREALTIME - $started_at }") s from sbatch to done"
}

# PIDs whose command line names path (read with builtins: a grep would find its own arguments).
processes_naming() {
  local path=$1 file args
  for file in /proc/[0-9]*/cmdline; do
    mapfile -d '' args 2>/dev/null <"$file" || continue
    [[ "${args[*]}" != *"$path"* ]] || echo "${file//[!0-9]/}"
  done
}

stop_cluster() {
  local folder started_at=$SECONDS
  folder=$(dirname "$SLURM_CONF")
  "$local_slurm" stop >/dev/null || fail "tools/slurm-local.sh stop failed"
  say "stop: $((SECONDS - started_at)) s"
  [ ! -e "$folder" ] || fail "stop left $folder"
  [ -z "$(processes_naming "$folder/")" ] || fail "processes of $folder still run: $(processes_naming "$folder/")"
  "$local_slurm" status >/dev/null && fail "status says running after stop"
  unset SLURM_CONF
}

round() {
  work=$(mktemp -d /tmp/pdamp-slurm-smoke.XXXXXX)
  chmod 755 "$work"
  start_cluster
  run_cancelled_array
  time_trivial_array
  stop_cluster
  rm -rf "$work"
  work=
}

main() {
  [[ "$rounds" =~ ^[1-9][0-9]*$ ]] || {
    echo "usage: tools/slurm-smoke.sh [ROUNDS]  (ROUNDS='$rounds': a positive integer)" >&2
    exit 2
  }
  if "$local_slurm" status >/dev/null 2>&1; then
    fail "a local Slurm is already running (tools/slurm-local.sh status); stop it first"
  fi
  trap on_exit EXIT
  local r
  for ((r = 1; r <= rounds; r++)); do
    say "round $r of $rounds"
    round
  done
  say "passed"
}

main
