#!/usr/bin/env bash
# Builds every libFuzzer harness of the project with clang (AddressSanitizer and UBSan on), each
# source compiled once and shared: the G-code front end's (gcode/fuzz/fuzz_gcode.cpp) and the
# command's input formats' (tools/fuzz/fuzz_*.cpp). Only what changed since the last build is
# compiled again. gcode/fuzz/run.sh and tools/fuzz/run.sh call it before they run.
#   tools/fuzz/build.sh [BUILD_DIR=build-fuzz]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build-fuzz}
objects_dir="$build/objects"
mkdir -p "$objects_dir" "$build/inputs"

flags=(-std=c++20 -O1 -g -fno-sanitize-recover=undefined -Iinclude -Igcode/include -Itools/cli)
# The command's parsers that the input harnesses reach; the G-code library whole.
cli_sources=(tools/cli/inputs/json_input.cpp tools/cli/inputs/numbers.cpp tools/cli/inputs/project.cpp
             tools/cli/inputs/stock.cpp tools/cli/inputs/tool_table.cpp tools/cli/pipeline/memory.cpp)
gcode_sources=(gcode/src/*.cpp)

# One object per source, named after its path; compiled (instrumented, no main) when missing or
# older than its source, on every core.
object_of() { local s=${1//\//_}; echo "$objects_dir/${s%.cpp}.o"; }
stale=()
for source in "${cli_sources[@]}" "${gcode_sources[@]}"; do
  object=$(object_of "$source")
  if [ ! -f "$object" ] || [ "$source" -nt "$object" ] || [ -n "$(find include gcode/include tools/cli gcode/src \
      -name '*.hpp' -newer "$object" -print -quit)" ]; then
    stale+=("$source")
  fi
done
export objects_dir
# ccache where installed (tools/quickstart.sh exports its base folder): a new clone of the same
# sources compiles nothing again.
launcher=$(command -v ccache || true)
export launcher
compile() {
  local source=$1 s=${1//\//_}
  $launcher clang++ "${@:2}" -fsanitize=fuzzer-no-link,address,undefined -c "$source" -o "$objects_dir/${s%.cpp}.o"
}
export -f compile
if [ ${#stale[@]} -gt 0 ]; then
  printf '%s\n' "${stale[@]}" | xargs -P "$(nproc)" -I{} bash -c 'compile "$@"' _ {} "${flags[@]}"
fi

gcode_objects=() cli_objects=()
for source in "${gcode_sources[@]}"; do gcode_objects+=("$(object_of "$source")"); done
for source in "${cli_sources[@]}"; do cli_objects+=("$(object_of "$source")"); done
link() {  # OUTPUT HARNESS OBJECTS...: the harness compiled on its own (so ccache keeps it), then linked
  local output=$1 harness=$2
  shift 2
  $launcher clang++ "${flags[@]}" -fsanitize=fuzzer,address,undefined -c "$harness" -o "$output.o"
  clang++ "${flags[@]}" -fsanitize=fuzzer,address,undefined "$output.o" "$@" -o "$output"
}
harnesses=("$build/fuzz_gcode gcode/fuzz/fuzz_gcode.cpp")
for h in stl tool_table project options machine; do harnesses+=("$build/inputs/fuzz_$h tools/fuzz/fuzz_$h.cpp"); done
pids=()
for entry in "${harnesses[@]}"; do
  read -r output harness <<< "$entry"
  # up to date: newer than its source and every object
  if [ -f "$output" ] && [ "$output" -nt "$harness" ] && [ ${#stale[@]} -eq 0 ]; then continue; fi
  if [ "$harness" = gcode/fuzz/fuzz_gcode.cpp ]; then
    link "$output" "$harness" "${gcode_objects[@]}" &
  else
    link "$output" "$harness" "${cli_objects[@]}" "${gcode_objects[@]}" &
  fi
  pids+=($!)
done
for pid in "${pids[@]}"; do wait "$pid"; done  # set -e: a failed link stops the script
