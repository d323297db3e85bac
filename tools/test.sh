#!/usr/bin/env bash
# Sets up, builds and runs the default test suite (README command 2; CI runs this).
# Usage: tools/test.sh [release|ci|sanitize]   (default: ci = warnings as errors)
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:-ci}
tools/setup.sh python3-matplotlib  # the study plot's test draws with it
tools/build.sh "$kind"
if [ "$kind" = sanitize ]; then
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
fi
ctest --test-dir "build/$kind" --output-on-failure --parallel "$(nproc)" --label-exclude slow
