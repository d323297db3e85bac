#!/usr/bin/env bash
# The LIGGGHTS peer benchmark (tools/bench/liggghts): the Table 2 bed shaken at 5 mm, 30.8 Hz
# in a static cylinder with the shaking applied in the container's frame, one core, at the
# same time step pdamp's soft engine uses for data/scenarios/bench/table2_shaken.ini, so the
# figures compare with tools/bench-soft.sh. Installs Debian's liggghts if missing (root).
# Usage: tools/bench-liggghts.sh   (env: SIZES, VARIANTS, VALIDATE as in run_bench.sh)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup.sh"
command -v liggghts >/dev/null || { apt-get update -qq && apt-get install -y -qq liggghts python3 >/dev/null; }
"$root/tools/build.sh" release >/dev/null
dt=$("$root/build/release/src/pdamp" check --scenario "$root/data/scenarios/bench/table2_shaken.ini" |
     sed -n 's/^# soft engine time step: \([0-9.e+-]*\) s.*/\1/p')
work="$root/build/bench/liggghts"
rm -rf "$work" && mkdir -p "$work" && cp "$root"/tools/bench/liggghts/* "$work"/
echo "LIGGGHTS at pdamp's time step dt = $dt s"
VALIDATE=${VALIDATE:-0} DT="$dt" "$work/run_bench.sh"
