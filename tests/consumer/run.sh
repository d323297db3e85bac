#!/usr/bin/env bash
# Installs the pdamp of build folder BUILD into a temporary prefix, builds the consumer
# project (tests/consumer) against it with find_package(pdamp 0.1), and runs it on
# data/scenarios/small.ini (hard engine, 0.01 s, the energy ledger must close).
# Usage: tests/consumer/run.sh BUILD
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: tests/consumer/run.sh BUILD" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Runs a step quietly; on failure shows its output.
quiet() {
  "$@" >"$work/log" 2>&1 || { cat "$work/log" >&2; echo "failed: $*" >&2; exit 1; }
}
quiet cmake --install "$build" --prefix "$work/prefix"
[ -x "$work/prefix/bin/pdamp" ] || { echo "the install has no bin/pdamp" >&2; exit 1; }
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
quiet cmake -S "$root/tests/consumer" -B "$work/build" "${generator[@]}" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release
quiet cmake --build "$work/build" --parallel 2
"$work/build/pdamp_consumer" "$root/data/scenarios/small.ini"
