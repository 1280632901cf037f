#!/usr/bin/env bash
# Runs the libFuzzer harnesses of the command's input formats (built by tools/fuzz/build.sh) each
# for a share of a bounded total time, with a fixed seed:
#   tools/fuzz/run.sh [SECONDS=60] [BUILD_DIR=build-fuzz]
#   stl         the STL reader, binary and ASCII (include/tridex/stl.hpp)
#   tool_table  the tool table, CAMotics schema (tools/cli/inputs/tool_table.cpp, json_input.cpp)
#   project     the .camotics project (tools/cli/inputs/project.cpp)
#   options     --stock, --envelope and --max-memory (tools/cli/inputs/stock.cpp, pipeline/memory.cpp)
#   machine     the machine file, kinematics included (gcode/src/machine_file.cpp, machine.cpp)
# Exit status 0: no crash in that time. A crash leaves its input as BUILD_DIR/<harness>-crash-*
# and stops the script with a non-zero status; turn it into a named case in
# tests/tools/test_bad_input.cpp with the input under tests/data/.
# (The G-code front end has its own harness: gcode/fuzz/run.sh.)
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
build=${2:-build-fuzz}
harnesses=(stl tool_table project options machine)
share=$(( seconds / ${#harnesses[@]} ))
[ "$share" -ge 1 ] || share=1
bash tools/fuzz/build.sh "$build"
# A fixed seed (FUZZ_SEED, default 1) makes CI explore the same inputs in the same order.
# The structured formats get a larger -max_len (deep nesting, long holder lists) and a dictionary of
# the classes the issue-36 audit found (tools/fuzz/*.dict).
for h in "${harnesses[@]}"; do
  mkdir -p "$build/inputs/corpus_$h"
  case "$h" in
    tool_table|project|machine) extra=(-max_len=65536 -dict=tools/fuzz/json.dict) ;;
    options) extra=(-max_len=4096 -dict=tools/fuzz/options.dict) ;;
    *) extra=(-max_len=4096) ;;
  esac
  echo "== fuzz_$h: ${share} s"
  if ! "$build/inputs/fuzz_$h" -seed="${FUZZ_SEED:-1}" -max_total_time="$share" -timeout=10 -rss_limit_mb=2048 \
      "${extra[@]}" -artifact_prefix="$build/$h-" -print_final_stats=1 \
      "$build/inputs/corpus_$h" "tools/fuzz/seeds/$h" >"$build/inputs/fuzz_$h.log" 2>&1; then
    tail -n 40 "$build/inputs/fuzz_$h.log" >&2
    echo "fuzz_$h found a crash: its input is $build/$h-crash-* (or -leak-, -timeout-, -oom-)" >&2
    exit 1
  fi
  grep -E 'stat::(number_of_executed_units|new_units_added)' "$build/inputs/fuzz_$h.log"
done
