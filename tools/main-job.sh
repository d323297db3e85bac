#!/usr/bin/env bash
# Sets up, builds and runs the main job (README command 1): the paper's Table 1 damper
# on both engines, stored in ./pdamp.sqlite, with a summary of each run.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
db=${PDAMP_DB:-pdamp.sqlite}
# The hard-sphere engine is still being built (issue 4): until it lands the job runs the
# soft model on the damper and the host alone on the hard model.
"$root/build/release/src/pdamp" run --scenario "$root/data/scenarios/table1.ini" --model soft --db "$db" "$@"
"$root/build/release/src/pdamp" run --scenario "$root/data/scenarios/table1.ini" --model hard --db "$db" \
  --set particles.count=0 "$@"
"$root/build/release/src/pdamp" runs --db "$db"
