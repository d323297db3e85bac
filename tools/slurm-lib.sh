# shellcheck shell=bash
# Shared by tools/slurm-local.sh and tools/slurm-smoke.sh (sourced).

# Polls a command every 0.2 s until it succeeds; fails after timeout_s with a message naming what.
# Usage: wait_for WHAT TIMEOUT_S COMMAND [ARGS...]
wait_for() {
  local what=$1 timeout_s=$2 deadline
  shift 2
  deadline=$((SECONDS + timeout_s))
  until "$@"; do
    ((SECONDS < deadline)) || {
      echo "${0##*/}: timed out after ${timeout_s} s waiting for $what" >&2
      return 1
    }
    sleep 0.2
  done
}
