#!/usr/bin/env bash
# The main job on the bundled example (run by tools/quickstart.sh demo after the build): simulate
# the 3+2 mold program from its CAMotics project (program, tool table and stock in one file) and
# write the machined solid, its picture and the report to out/. The command prints a two-line
# summary on stdout (warnings, if any, on stderr).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p out
exec ./build/tools/tridex simulate gcode/examples/mold_3plus2.camotics \
  -o out/example.stl --png out/example.png --report out/example.json
