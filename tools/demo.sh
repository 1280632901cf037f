#!/usr/bin/env bash
# The main job on the bundled example (run by tools/quickstart.sh demo after the build).
set -euo pipefail
cd "$(dirname "$0")/.."
./build/tools/tridex-kernel-demo
