#!/usr/bin/env bash
# Runs clang-tidy (.clang-tidy's checks) with build/ci's compile commands.
# Usage: tools/tidy.sh [FILE...]   (default: every .cpp under src/; tools/build.sh ci first;
#        PDAMP_TIDY_BUILD=DIR for another build folder with compile_commands.json)
# Prints what it finds; exit 0 if nothing, 1 if anything, 2 on a usage error.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
db=${PDAMP_TIDY_BUILD:-$root/build/ci}
if [ ! -f "$db/compile_commands.json" ]; then
  echo "tools/tidy.sh: no $db/compile_commands.json: run tools/build.sh ci first" >&2
  exit 2
fi
command -v clang-tidy >/dev/null || { echo "tools/tidy.sh: clang-tidy is not installed (apt-get install clang-tidy)" >&2; exit 2; }
files=("$@")
[ ${#files[@]} -gt 0 ] || mapfile -t files < <(cd "$root" && find src -name '*.cpp' | sort)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
for file in "${files[@]}"; do
  # Only .clang-tidy's checks: the compiler's own warnings (clang's differ from GCC's, which
  # the build makes errors) are off.
  clang-tidy --quiet -p "$db" --extra-arg=-Wno-everything --extra-arg=-Wno-error "$file" >"$log" 2>/dev/null || true
  if grep -q 'warning:\|error:' "$log"; then
    grep -A3 'warning:\|error:' "$log"
    status=1
  fi
done
exit "$status"
