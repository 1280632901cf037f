#!/usr/bin/env bash
# Runs the libFuzzer harness of the G-code front end for a bounded time (tools/fuzz/build.sh builds
# it with clang, with the other harnesses, compiling only what changed).
#   gcode/fuzz/run.sh [SECONDS=60] [BUILD_DIR=build-fuzz]
# Exit status 0: no crash in that time. A crash leaves its input as BUILD_DIR/crash-* (and the
# status is non-zero); turn it into a named case in tests/gcode/test_bad_input.cpp.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
build=${2:-build-fuzz}
mkdir -p "$build/fuzz_corpus"
bash tools/fuzz/build.sh "$build"
# A fixed seed (FUZZ_SEED, default 1) makes CI explore the same inputs in the same order.
exec "$build/fuzz_gcode" -seed="${FUZZ_SEED:-1}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
  -dict=gcode/fuzz/gcode.dict -artifact_prefix="$build/" -print_final_stats=1 \
  "$build/fuzz_corpus" gcode/fuzz/seeds tests/data/gcode/linuxcnc
