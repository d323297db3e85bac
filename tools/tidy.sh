#!/usr/bin/env bash
# Runs clang-tidy (.clang-tidy's checks) with build/ci's compile commands.
# Usage: tools/tidy.sh [FILE...]   (default: every source file build/ci compiles: src/,
#        tests/, tools/bench/; tools/build.sh ci first; PDAMP_TIDY_BUILD=DIR for another
#        build folder with compile_commands.json). Files are checked side by side, one per core.
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
if [ ${#files[@]} -eq 0 ]; then
  mapfile -t files < <(python3 -c 'import json, sys
for entry in json.load(open(sys.argv[1])): print(entry["file"])' "$db/compile_commands.json" | sort -u)
fi
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
# Only .clang-tidy's checks: the compiler's own warnings (clang's differ from GCC's, which
# the build makes errors) are off. Each file's findings go to a log of its own.
printf '%s\n' "${files[@]}" | nl -nln -w1 -s' ' | xargs -P "$(nproc)" -L1 sh -c \
  'clang-tidy --quiet -p "$0" --extra-arg=-Wno-everything --extra-arg=-Wno-error "$3" >"$1/$2.log" 2>/dev/null || true' \
  "$db" "$logs"
# A header's findings come once, however many files include it.
findings=$(cat "$logs"/*.log | grep 'warning:\|error:' | sort -u || true)
[ -z "$findings" ] && exit 0
echo "$findings"
exit 1
