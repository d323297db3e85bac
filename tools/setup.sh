#!/usr/bin/env bash
# Installs what pdamp needs to build and test on Debian 12, if it is missing.
# Idempotent: installs nothing when everything is present. Needs root (or sudo).
# Usage: tools/setup.sh [extra Debian packages, e.g. valgrind for tools/bench-hard.sh --counts]
set -euo pipefail

# python3-matplotlib: the test of tools/plot_rom.py. python3-vtk9: VTK's own reader checks
# the snapshots the tests write (tools/check_snapshots.py).
packages=(g++ cmake make libboost-dev libboost-program-options-dev libeigen3-dev libsqlite3-dev doctest-dev sqlite3
  python3-matplotlib python3-vtk9 "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "setup: installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi
