#!/usr/bin/env bash
# Sets up, builds and runs the main job (README command 1): the paper's Table 1 damper on
# both models from one settled bed (`pdamp compare`, hard model with the restitution
# calibrated from the soft law), stored in ./pdamp.sqlite (or $PDAMP_DB); prints the
# side-by-side summary and the stored runs. Extra arguments go to `pdamp compare`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup.sh"
"$root/tools/build.sh" release >/dev/null
db=${PDAMP_DB:-pdamp.sqlite}
"$root/build/release/src/pdamp" compare --scenario "$root/data/scenarios/table1.ini" \
  --set hard.restitution=calibrated --db "$db" "$@"
"$root/build/release/src/pdamp" runs --db "$db"
