#!/usr/bin/env bash
# Builds the scenario loader's libFuzzer target with clang in build/fuzz (instrumented, with
# ASan and UBSan) and runs it, from tests/fuzz/corpus (hostile cases) and data/scenarios, for a fixed time.
# Usage: tools/fuzz.sh [seconds]   (default 60; .ci/run runs it)
# Inputs the fuzzer finds interesting go to build/fuzz/corpus, not into the tree. A crash,
# an input taking over -timeout seconds or a process past -rss_limit_mb fails the script,
# the input saved as build/fuzz/crash-*, timeout-* or oom-* (once fixed, add it to the corpus).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
[ -f build/fuzz/CMakeCache.txt ] || CC=clang CXX=clang++ cmake -S . -B build/fuzz "${generator[@]}" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPDAMP_FUZZ=ON -DBUILD_TESTING=OFF >/dev/null
cmake --build build/fuzz --target pdamp_fuzz_scenario --parallel "$(nproc)"
mkdir -p build/fuzz/corpus
build/fuzz/tests/fuzz/pdamp_fuzz_scenario -max_total_time="$seconds" -timeout=10 -rss_limit_mb=1024 \
  -max_len=8192 -dict=tests/fuzz/scenario.dict -artifact_prefix=build/fuzz/ -print_final_stats=1 \
  build/fuzz/corpus tests/fuzz/corpus data/scenarios
