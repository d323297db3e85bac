#!/usr/bin/env bash
# Configures and builds pdamp. Usage: tools/build.sh [release|ci|sanitize]
#   release   optimised build in build/release (default)
#   ci        like release, warnings are errors, in build/ci
#   sanitize  AddressSanitizer + UndefinedBehaviorSanitizer, in build/sanitize
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:-release}
case "$kind" in
  release)  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo) ;;
  ci)       flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DPDAMP_WARNINGS_AS_ERRORS=ON) ;;
  # -O1 keeps the sanitized suite within minutes; assertions stay on.
  sanitize) flags=(-DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g" -DPDAMP_SANITIZE=ON -DPDAMP_WARNINGS_AS_ERRORS=ON) ;;
  *) echo "usage: tools/build.sh [release|ci|sanitize]" >&2; exit 2 ;;
esac
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
[ -f "build/$kind/CMakeCache.txt" ] || cmake -S . -B "build/$kind" "${generator[@]}" "${flags[@]}" >/dev/null
cmake --build "build/$kind" --parallel "$(nproc)"
