#!/usr/bin/env bash
# CTest's html_report_browser: the --html page in Debian's headless Chromium (report_test.mjs).
#   tests/html/run.sh TRIDEX OUT_DIR
# Skips (exit 77, shown by CTest as skipped) when Chromium, Node.js or the npm packages are
# missing; tools/quickstart.sh test installs all three (tools/deps/test.txt, `npm ci`).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tridex=$1 out=$2
chromium=${TRIDEX_CHROMIUM:-/usr/bin/chromium}
skip() { echo "SKIPPED: $*"; exit 77; }
[ -x "$chromium" ] || skip "no Chromium at $chromium (apt-get install chromium, see tools/deps/test.txt)"
command -v node > /dev/null || skip "no Node.js (apt-get install nodejs npm)"
[ -d "$here/node_modules/puppeteer-core" ] || skip "puppeteer-core is not installed (npm ci --prefix tests/html)"
rm -rf "$out"
mkdir -p "$out"
exec node "$here/report_test.mjs" "$tridex" "$out" "$chromium"
