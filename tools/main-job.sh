#!/usr/bin/env bash
# Sets up, builds and runs the main job (README command 1): the paper's Table 1 damper
# on both engines, stored in ./pdamp.sqlite, with a summary of each run.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
db=${PDAMP_DB:-pdamp.sqlite}
for model in soft hard; do
  "$root/build/release/src/pdamp" run --scenario "$root/data/scenarios/table1.ini" --model "$model" --db "$db" "$@"
done
"$root/build/release/src/pdamp" runs --db "$db"
