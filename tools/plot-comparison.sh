#!/usr/bin/env bash
# Draws a stored comparison (tools/plot_comparison.py) with Debian's Python and matplotlib,
# installing python3-matplotlib if it is missing (root or sudo).
# Usage: tools/plot-comparison.sh [--db pdamp.sqlite] [--comparison ID] [--out FILE.png|.svg]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if ! /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq python3-matplotlib >/dev/null
fi
exec /usr/bin/python3 "$root/tools/plot_comparison.py" "$@"
