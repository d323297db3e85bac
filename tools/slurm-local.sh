#!/usr/bin/env bash
# A real single-node Slurm on this machine, for the tests of studies on Slurm (issue 26):
# Debian 12's munge and slurm-wlm (22.05) run as root, every file (config, munge key and socket,
# state, spool, logs, PID files) in one temporary folder, nothing written to /etc.
# Usage: tools/slurm-local.sh start|stop|status
#   start   installs the packages if missing, starts munged, slurmctld and slurmd, waits until
#           the node is idle, prints the `export SLURM_CONF=...` line (also in FOLDER/slurm.env).
#           Already running: says so, exit 0.
#   stop    cancels the cluster's jobs, stops the daemons `start` started (by PID, checked against
#           the folder in their command line), removes the folder. Not running: says so, exit 0.
#   status  what runs; exit 0 running, 1 partly running (stop cleans up), 3 not started.
# Environment: PDAMP_SLURM_STATE_FILE (default /run/pdamp-slurm-local: holds the folder's path),
#   PDAMP_SLURM_START_TIMEOUT_S (default 60: how long start waits for the idle node).
# Without slurmdbd (not set up here: it needs MySQL) `sacct` has no accounting data; finished jobs
# stay in `squeue`/`scontrol show job` for MinJobAge and in the job-completion file for good,
# which `sacct --completion` reads (job records only, no steps).
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=tools/slurm-lib.sh
source "$repo/tools/slurm-lib.sh"
state_file=${PDAMP_SLURM_STATE_FILE:-/run/pdamp-slurm-local}
start_timeout_s=${PDAMP_SLURM_START_TIMEOUT_S:-60}
cluster_name=pdamp-local
daemons=(slurmd slurmctld munged) # stop order: the node, the controller, then authentication

die() {
  echo "slurm-local: $*" >&2
  exit 1
}
say() { echo "slurm-local: $*"; }

# Daemons run as root (SlurmUser=root keeps the sandbox to one user); with sudo, run ourselves
# again, passing on the settings the caller made (sudo resets the environment).
become_root() {
  [ "$(id -u)" -eq 0 ] && return
  command -v sudo >/dev/null || die "needs root to run munged, slurmctld and slurmd, and sudo is not installed"
  local settings=() name
  for name in PDAMP_SLURM_STATE_FILE PDAMP_SLURM_START_TIMEOUT_S; do
    [ -z "${!name:-}" ] || settings+=("$name=${!name}")
  done
  exec sudo "${settings[@]}" "$0" "$@"
}

install_packages() {
  "$repo/tools/setup.sh" slurm-wlm munge || die "tools/setup.sh slurm-wlm munge failed: Slurm and munge cannot be installed"
  local tool
  for tool in mungekey munged munge unmunge slurmctld slurmd sinfo squeue scancel; do
    command -v "$tool" >/dev/null || die "'$tool' is missing after tools/setup.sh slurm-wlm munge"
  done
}

# The folder of the running instance, from the state file; empty when none is recorded.
recorded_folder() {
  if [ -f "$state_file" ]; then cat "$state_file"; fi
}

# The PID this script recorded at launch. Each daemon writes its own PID file elsewhere
# (daemon_pid_file): a daemon replaces that file during start, and a check reading it then found
# it missing (CI, munged).
pid_file() {
  local folder=$1 daemon=$2
  echo "$folder/run/$daemon.pid"
}

daemon_pid_file() {
  local folder=$1 daemon=$2
  echo "$folder/run/$daemon.own.pid"
}

# PID of the daemon when it runs and is ours: PIDs are reused, so its command line must name the
# folder (each daemon gets an explicit -f/--socket path inside it).
daemon_pid() {
  local folder=$1 daemon=$2 file pid
  file=$(pid_file "$folder" "$daemon")
  [ -s "$file" ] || return 1
  pid=$(<"$file")
  tr '\0' ' ' 2>/dev/null <"/proc/$pid/cmdline" | grep -qF "$folder/" || return 1
  echo "$pid"
}

running_count() {
  local folder=$1 daemon n=0
  for daemon in "${daemons[@]}"; do
    daemon_pid "$folder" "$daemon" >/dev/null && n=$((n + 1))
  done
  echo "$n"
}

# The slurm.conf. Everything cgroup-based is off (proctrack/linuxproc, task/none): containers and
# CI machines rarely delegate cgroups. No slurmdbd: job-completion records go to a text file.
# NodeAddr and the controller's address are 127.0.0.1 so that nothing depends on name resolution.
write_slurm_conf() {
  local folder=$1 node=$2 memory_mib=$3
  cat >"$folder/slurm.conf" <<EOF
ClusterName=$cluster_name
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$folder/munge/munge.socket
StateSaveLocation=$folder/state
SlurmdSpoolDir=$folder/spool
SlurmctldPidFile=$(daemon_pid_file "$folder" slurmctld)
SlurmdPidFile=$(daemon_pid_file "$folder" slurmd)
SlurmctldLogFile=$folder/log/slurmctld.log
SlurmdLogFile=$folder/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$folder/log/jobcomp.txt
# A restarted slurmd rejoins on its own; cancelled tasks get 5 s between SIGTERM and SIGKILL.
ReturnToService=2
KillWait=5
# Small, so that tools/slurm-study-test.sh's 8 points go as two job arrays (Slurm's default: 1001).
MaxArraySize=5
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mib State=UNKNOWN
PartitionName=pdamp Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
  chmod 644 "$folder/slurm.conf"
}

# slurmd's own measure of the memory, so that the node is not drained for "Low RealMemory".
node_memory_mib() {
  slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p'
}

# Runs a daemon in its foreground mode, in the background and in its own session (a closing
# terminal or a signal to the caller's process group does not reach it), and records its PID. The
# PID is known at once, so a daemon that dies during start is noticed at once, PID file or not.
# Standard streams: /dev/null and a file, as an inherited pipe would keep a caller (CTest, CI)
# waiting for end-of-file long after this script returned.
launch() {
  local folder=$1 daemon=$2
  shift 2
  setsid "$daemon" "$@" </dev/null >>"$folder/log/$daemon.out" 2>&1 &
  echo "$!" >"$(pid_file "$folder" "$daemon")"
}

# The waits below end early when a daemon has died: its log says why (the EXIT trap shows it).
fail_if_died() {
  local folder=$1 daemon=$2
  ! process_gone "$(<"$(pid_file "$folder" "$daemon")")" || die "$daemon exited during start"
}

# Its own key and socket: the system's munged (if any) and /etc/munge are left alone.
start_munged() {
  local folder=$1
  mkdir -p "$folder/munge"
  chmod 755 "$folder/munge" # clients of other users reach the socket
  mungekey --create --keyfile="$folder/munge/munge.key"
  # --force: munged refuses a socket path under world-writable /tmp otherwise.
  launch "$folder" munged --foreground --force --socket="$folder/munge/munge.socket" \
    --key-file="$folder/munge/munge.key" --pid-file="$(daemon_pid_file "$folder" munged)" \
    --log-file="$folder/log/munged.log" --seed-file="$folder/munge/munged.seed"
  wait_for "munged to answer" 10 munge_answers "$folder"
}

munge_answers() {
  local folder=$1 socket=$1/munge/munge.socket
  munge -n -S "$socket" 2>/dev/null | unmunge -S "$socket" >/dev/null 2>&1 && return
  fail_if_died "$folder" munged
  return 1
}

start_slurm_daemons() {
  local folder=$1 node=$2
  # -c: a new cluster, no saved state to look for.
  launch "$folder" slurmctld -D -c -f "$folder/slurm.conf"
  wait_for "slurmctld to answer" 20 controller_answers "$folder"
  # -N: the node's name in slurm.conf, whatever the host name says.
  launch "$folder" slurmd -D -f "$folder/slurm.conf" -N "$node"
}

controller_answers() {
  local folder=$1
  scontrol ping >/dev/null 2>&1 && return
  fail_if_died "$folder" slurmctld
  return 1
}

node_idle() {
  local folder=$1 node=$2
  [ "$(sinfo -h -N -n "$node" -o %T 2>/dev/null)" = idle ] && return
  fail_if_died "$folder" slurmctld
  fail_if_died "$folder" slurmd
  return 1
}

# Slurm's default ports (SlurmctldPort 6817, SlurmdPort 6818): taken means another Slurm runs here,
# and our daemons would die on "Address already in use".
check_ports_free() {
  local port
  for port in 6817 6818; do
    if (echo >"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      die "port $port on 127.0.0.1 is taken: another Slurm runs on this machine; stop it first"
    fi
  done
}

show_logs() {
  local folder=$1 log
  # sinfo retries for 9 s against a controller that is down.
  if scontrol ping >/dev/null 2>&1; then sinfo -N -l -R >&2 || true; fi
  for log in "$folder"/log/*.log "$folder"/log/*.out; do
    [ -f "$log" ] || continue
    echo "--- last lines of $log" >&2
    tail -n 20 "$log" >&2
  done
}

start_failed() {
  local folder=$1
  show_logs "$folder"
  stop >&2 || true
  echo "slurm-local: start failed (logs of $folder above); what it started is stopped" >&2
  exit 1
}

start() {
  local folder node memory_mib started_at=$SECONDS
  folder=$(recorded_folder)
  if [ -n "$folder" ] && [ "$(running_count "$folder")" -eq "${#daemons[@]}" ]; then
    say "already running in $folder"
    cat "$folder/slurm.env"
    return 0
  fi
  [ -z "$folder" ] || {
    say "cleaning up what is left of the instance in $folder"
    stop
  }
  install_packages
  check_ports_free
  node=$(hostname -s)
  memory_mib=$(node_memory_mib)
  [[ "$memory_mib" =~ ^[0-9]+$ ]] || die "slurmd -C reports no RealMemory: $(slurmd -C 2>&1)"
  folder=$(mktemp -d /tmp/pdamp-slurm.XXXXXX)
  echo "$folder" >"$state_file" # first, so that stop finds whatever gets started
  chmod 755 "$folder"            # users other than root read slurm.conf
  mkdir -p "$folder"/{run,log,state,spool}
  export SLURM_CONF=$folder/slurm.conf
  echo "export SLURM_CONF=$SLURM_CONF" >"$folder/slurm.env"
  write_slurm_conf "$folder" "$node" "$memory_mib"
  # Any failure from here on: the logs, then stop what did start.
  # shellcheck disable=SC2064 # the folder is fixed now
  trap "start_failed '$folder'" EXIT
  start_munged "$folder"
  start_slurm_daemons "$folder" "$node"
  wait_for "node $node to be idle in sinfo" "$start_timeout_s" node_idle "$folder" "$node"
  trap - EXIT
  say "node $node idle after $((SECONDS - started_at)) s; folder $folder"
  cat "$folder/slurm.env"
}

# Cancels every job of this cluster and waits until slurmd has ended them, so that no job step
# outlives the daemons. Bounded: KillWait (5 s) plus slack.
cancel_jobs() {
  local folder=$1 jobs
  daemon_pid "$folder" slurmctld >/dev/null || return 0
  jobs=$(squeue -h -o %F 2>/dev/null | sort -u | tr '\n' ' ')
  [ -n "${jobs// /}" ] || return 0
  say "cancelling jobs $jobs"
  # shellcheck disable=SC2086 # one argument per job ID
  scancel $jobs || true
  wait_for "jobs to end" 30 queue_empty || echo "slurm-local: jobs still listed: $(squeue -h 2>&1)" >&2
}

queue_empty() {
  [ -z "$(squeue -h 2>/dev/null)" ]
}

stop_daemon() {
  local folder=$1 daemon=$2 pid
  pid=$(daemon_pid "$folder" "$daemon") || return 0
  kill -TERM "$pid" 2>/dev/null || true
  if ! wait_for "$daemon (PID $pid) to exit" 15 process_gone "$pid"; then
    kill -KILL "$pid" 2>/dev/null || true
    wait_for "$daemon (PID $pid) to die" 5 process_gone "$pid" || die "$daemon (PID $pid) survives SIGKILL"
  fi
  say "stopped $daemon (PID $pid)"
}

# A zombie counts as gone: its parent is init, which may be slow to reap it, or never (containers).
process_gone() {
  local pid=$1 state
  state=$(awk '/^State:/ { print $2 }' "/proc/$pid/status" 2>/dev/null) || return 0
  [ -z "$state" ] || [ "$state" = Z ]
}

# Job processes that outlived their job (proctrack/linuxproc misses daemonised children; a
# slurmctld that died leaves jobs uncancelled). Slurmd's job step daemons (slurmstepd) carry the
# cluster's SLURM_CONF in their environment, job processes also its SLURM_CLUSTER_NAME: the name
# tells them from a caller that merely exported SLURM_CONF inside another cluster's job.
kill_leftovers() {
  local folder=$1 file pid pids=()
  # One grep over all environments (-z: NUL-separated entries); a loop of subshells takes seconds.
  while IFS= read -r file; do
    pid=${file//[!0-9]/}
    if [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = slurmstepd ] ||
      grep -qzxF "SLURM_CLUSTER_NAME=$cluster_name" "$file" 2>/dev/null; then
      pids+=("$pid")
    fi
  done < <(grep -lzxF "SLURM_CONF=$folder/slurm.conf" /proc/[0-9]*/environ 2>/dev/null || true)
  ((${#pids[@]})) || return 0
  say "killing job processes that outlived their jobs: ${pids[*]}"
  kill -KILL "${pids[@]}" 2>/dev/null || true
}

stop() {
  local folder daemon
  folder=$(recorded_folder)
  if [ -z "$folder" ]; then
    say "not running"
    return 0
  fi
  # The folder is removed below: refuse anything but one that start created.
  [[ "$folder" == /tmp/pdamp-slurm.* ]] || die "$state_file names '$folder', not a /tmp/pdamp-slurm.* folder"
  export SLURM_CONF=$folder/slurm.conf
  cancel_jobs "$folder"
  for daemon in "${daemons[@]}"; do
    stop_daemon "$folder" "$daemon"
  done
  kill_leftovers "$folder"
  rm -rf "$folder"
  rm -f "$state_file"
  say "removed $folder"
}

status() {
  local folder daemon pid n
  folder=$(recorded_folder)
  if [ -z "$folder" ]; then
    say "not started"
    return 3
  fi
  say "folder $folder"
  for daemon in "${daemons[@]}"; do
    if pid=$(daemon_pid "$folder" "$daemon"); then say "$daemon running, PID $pid"; else say "$daemon not running"; fi
  done
  n=$(running_count "$folder")
  if ((n < ${#daemons[@]})); then
    say "partly running: tools/slurm-local.sh stop cleans up"
    return 1
  fi
  export SLURM_CONF=$folder/slurm.conf
  sinfo -N
  squeue
  cat "$folder/slurm.env"
}

main() {
  case "${1:-}" in
    start | stop | status) ;;
    *)
      echo "usage: tools/slurm-local.sh start|stop|status" >&2
      exit 2
      ;;
  esac
  [[ "$start_timeout_s" =~ ^[1-9][0-9]*$ ]] || {
    echo "slurm-local: PDAMP_SLURM_START_TIMEOUT_S='$start_timeout_s': a whole number of seconds, at least 1" >&2
    exit 2
  }
  become_root "$@"
  "$1"
}

main "$@"
