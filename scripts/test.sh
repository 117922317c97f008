#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine (run as root so missing
# packages can be installed):
#   0. check the formatting (scripts/check-format.sh);
#   1. build with warnings as errors and run every test (ctest);
#   2. build again with AddressSanitizer + UndefinedBehaviorSanitizer and rerun the tests;
#   3. build the libFuzzer targets with clang and run each for CSW_FUZZ_SECONDS (default 30).
# Set CSW_TEST_QUICK=1 to run step 1 only.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/install-deps.sh
jobs=$(nproc)
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
export CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-5G}
# Paths relative to the checkout, so a fresh clone elsewhere reuses the cache.
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root} CCACHE_NOHASHDIR=${CCACHE_NOHASHDIR:-true}
start=$(date +%s)
stamp() { echo "== [$(( $(date +%s) - start )) s] $*"; }

stamp "format (.clang-format)"
bash scripts/check-format.sh

stamp "build (warnings as errors)"
cmake -S . -B build/ci -G Ninja -DCSW_WERROR=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/ci -j"$jobs"
stamp "tests"
# The per-test timeout is a guard against hangs, not a speed check (speed is
# measured in bench/): the two acceptance runs (phasing over 100 sentences,
# synthesis of 30) take 250-600 s each on a 2-core VM, and CI hosts have run
# the suite up to 8x slower than that.
summary=$(mktemp)
(cd build/ci && QT_QPA_PLATFORM=offscreen ctest --output-on-failure -j"$jobs" --timeout 2400) | tee "$summary"
count_tests() { sed -n 's/.*tests passed, \([0-9]*\) tests failed out of \([0-9]*\).*/\2 \1/p' "$summary" | tail -n 1; }
read -r total1 failed1 <<<"$(count_tests)"

if [ "${CSW_TEST_QUICK:-0}" = 1 ]; then
  stamp "quick mode: done"
  echo "tests: $((total1 - failed1)) passed, $failed1 failed"
  exit 0
fi

stamp "build (ASan + UBSan)"
# Debug (assertions on) but at -O1, as the AddressSanitizer documentation advises:
# at -O0 the Eigen-heavy tests ran for 23 minutes. Warnings are errors in the plain
# build above; here they are not, since GCC at -O1 with the sanitizers warns
# spuriously (maybe-uninitialized, stringop-overflow).
cmake -S . -B build/asan -G Ninja -DCSW_WERROR=OFF -DCSW_SANITIZE=ON -DCSW_BUILD_BENCH=OFF \
  -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g" "-DCMAKE_C_FLAGS_DEBUG=-O1 -g" >/dev/null
cmake --build build/asan -j"$jobs"
stamp "tests under ASan + UBSan"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0
export LSAN_OPTIONS=suppressions=$root/tests/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The virtual-cuer acceptance runs (every test with "Acceptance" in its name:
# many simulated sentences through simulate, import, fit, invert, key recognition
# and phasing) are left out here: under ASan their Eigen-heavy simulations run
# for over 10 minutes each. Every code path they drive is exercised under the
# sanitizers by the smaller tests of the same modules (on fewer takes).
(cd build/asan && QT_QPA_PLATFORM=offscreen ctest --output-on-failure -j"$jobs" --timeout 2400 \
  -E 'Acceptance') | tee "$summary"
read -r total2 failed2 <<<"$(count_tests)"

stamp "build fuzzers (clang, libFuzzer + ASan + UBSan)"
CC=clang CXX=clang++ cmake -S . -B build/fuzz -G Ninja -DCSW_FUZZ=ON -DCSW_BUILD_TESTS=OFF \
  -DCSW_BUILD_GUI=OFF -DCSW_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/fuzz -j"$jobs" --target csw_fuzzers
secs=${CSW_FUZZ_SECONDS:-30}
for f in build/fuzz/fuzz/fuzz_*; do
  [ -x "$f" ] || continue
  name=$(basename "$f")
  seeds="$root/fuzz/seeds/${name#fuzz_}"
  work="build/fuzz/corpus-${name#fuzz_}"
  mkdir -p "$work"
  stamp "fuzz $name for ${secs}s"
  "$f" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "$work" \
    $( [ -d "$seeds" ] && echo "$seeds" ) 2>&1 | tail -n 12
done
stamp "all test stages passed"
rm -f "$summary"
# Plain closing line: both ctest runs (plain and ASan+UBSan) together.
echo "tests: $((total1 + total2 - failed1 - failed2)) passed, $((failed1 + failed2)) failed"
