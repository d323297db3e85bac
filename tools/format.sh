#!/usr/bin/env bash
# Formats the C++ tree with .clang-format (Debian 12's clang-format 14).
# Usage: tools/format.sh [--check]   (--check: change nothing, fail on any file that would change)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || tools/setup.sh clang-format
mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
if [ "${1:-}" = --check ]; then
  clang-format --dry-run --Werror "${files[@]}"
else
  clang-format -i "${files[@]}"
fi
