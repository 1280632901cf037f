#!/usr/bin/env bash
# tridex quick start.
#   tools/quickstart.sh demo   install what is missing, build, run the main job on the bundled example
#   tools/quickstart.sh test   install what is missing, build, run the whole test suite (also under
#                              ASan+UBSan)
# Works on a fresh Debian 12 machine as root or with sudo. Builds go to build/ and build-asan/.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-demo}
case "$mode" in demo|test) ;; *) echo "usage: $0 demo|test" >&2; exit 2 ;; esac

# Each stage's header says when it began (seconds since the start), so a slow stage shows in the log.
stage() { echo "== $* [${SECONDS} s]"; }

sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
lists=(tools/deps/build.txt)
[ "$mode" = test ] && lists+=(tools/deps/test.txt)
mapfile -t wanted < <(grep -hv '^\s*#' "${lists[@]}" | sed '/^\s*$/d')
missing=()
for p in "${wanted[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  stage "installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The browser tests' driver (tests/html: puppeteer-core, pinned by its package-lock.json; it uses
# Debian's chromium from test.txt and downloads no browser).
if [ "$mode" = test ]; then
  if ! command -v npm > /dev/null; then
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends nodejs npm
  fi
  stage "npm ci (tests/html)"
  (cd tests/html && npm ci --no-audit --no-fund --loglevel=error)
fi

jobs=$(nproc)
# ccache, where installed (the test mode installs it): a second run on the same machine compiles
# only what changed. CCACHE_BASEDIR makes the compile commands relative to this clone, so another
# clone of the same sources hits the same cache; with NOHASHDIR the debug info's build folder is
# not part of the key (stack traces still name the sources).
cache=()
if command -v ccache > /dev/null; then
  cache=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
fi
if [ "$mode" = demo ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTRIDEX_BUILD_TESTS=OFF -DTRIDEX_BUILD_BENCH=OFF "${cache[@]}"
  cmake --build build -j "$jobs"
  exec bash tools/demo.sh
fi

# The house rules first: they take seconds and name the file and line of every breach.
stage "house rules: lengths, one thread pool, one machine registry (tools/check_structure.py)"
python3 tools/check_structure.py
stage "formatting (.clang-format, clang-format $(clang-format --version | grep -o '[0-9][0-9.]*' | head -1))"
{ git ls-files -z '*.hpp' '*.cpp' '*.h' 2> /dev/null ||
  find include gcode tools tests bench \( -name '*.hpp' -o -name '*.cpp' -o -name '*.h' \) -print0; } |
  xargs -0 -r clang-format --dry-run --Werror

# -DTRIDEX_BUILD_TESTS=ON even where build/ was configured by the demo without tests, and
# --no-tests=error: a build with no tests must not pass.
stage "release build"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTRIDEX_BUILD_TESTS=ON -DTRIDEX_BUILD_BENCH=ON "${cache[@]}"
cmake --build build -j "$jobs"

# The release suites and the fuzzers' build run beside the ASan+UBSan build: a build leaves cores
# idle while it links, and a test run while its longest suite finishes; the machine's time is the
# same, the wait shorter. Their output is shown once the build is done.
stage "release tests and the fuzzers' build (clang, libFuzzer), beside the ASan+UBSan build"
ctest --test-dir build --output-on-failure --no-tests=error -j "$jobs" > build/ctest.log 2>&1 &
release_tests=$!
bash tools/fuzz/build.sh build-fuzz > build/fuzz-build.log 2>&1 &
fuzz_build=$!
# -O1 -g1 (the level AddressSanitizer's documentation suggests): half the compile time of -O2 -g
# on the kernel's tests (test_zmap.cpp: 27 s against 50 s of CPU); stack traces keep file and line.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRIDEX_SANITIZE=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DTRIDEX_BUILD_TESTS=ON -DTRIDEX_BUILD_BENCH=OFF "${cache[@]}"
cmake --build build-asan -j "$jobs"
release_status=0
wait "$release_tests" || release_status=$?
stage "release tests"
cat build/ctest.log
[ "$release_status" -eq 0 ] || exit "$release_status"
fuzz_build_status=0
wait "$fuzz_build" || fuzz_build_status=$?
if [ "$fuzz_build_status" -ne 0 ]; then
  cat build/fuzz-build.log >&2
  echo "the fuzzers' build failed (its log above)" >&2
  exit 1
fi

# The fuzzers are bounded in time, not in work: they run on one core beside the sanitizer
# suites, which leave a core idle while their longest suite finishes.
stage "ASan+UBSan tests, beside the bounded fuzzers (G-code front end; STL, tool table, project, options, machine file)"
( bash gcode/fuzz/run.sh 60 build-fuzz > build-fuzz/gcode.log 2>&1 && bash tools/fuzz/run.sh 60 build-fuzz > build-fuzz/inputs.log 2>&1 ) &
fuzzers=$!
status=0
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 LSAN_OPTIONS=suppressions=$PWD/tools/lsan.supp \
  ctest --test-dir build-asan --output-on-failure --no-tests=error -j "$jobs" | tee build-asan/ctest.log || status=$?
fuzz_status=0
wait "$fuzzers" || fuzz_status=$?
cat build-fuzz/gcode.log build-fuzz/inputs.log 2> /dev/null | grep -E '^(==|stat::|#[0-9]+ +DONE|Done)|crash|ERROR' || true
if [ "$fuzz_status" -ne 0 ]; then
  tail -n 60 build-fuzz/gcode.log build-fuzz/inputs.log 2> /dev/null >&2
  echo "a fuzzer failed (its log above; its input under build-fuzz/)" >&2
  exit 1
fi
[ "$status" -eq 0 ] || exit "$status"

# One closing line for both suites (ctest's own summaries are further up).
total=$(( $(cat build/ctest.log build-asan/ctest.log | sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' | paste -sd+) ))
echo "tests: $total passed, 0 failed [${SECONDS} s]"
