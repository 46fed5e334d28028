#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run of the test suite (issue #12, docs/hardening.md): configures
# the shared clang sanitizer tree (scripts/san-configure.sh, default build-san), builds the test binaries of
# SANITIZE_AREAS and runs them with ctest. Suppressions are in fuzz/sanitizer-suppressions/, each justified
# there. scripts/ci-hardening.sh runs it for the CI areas; `make sanitize` for all areas.
# Usage: scripts/sanitize.sh [build-dir]   env: SANITIZE_AREAS (default: all areas), JOBS, LEAK_CHECK (0).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-san}"
areas="${SANITIZE_AREAS:-runtime kernels analysis cli farm hardening surface gabor mix serve cs oiio}"
jobs="${JOBS:-$(nproc)}"
supp="$here/fuzz/sanitizer-suppressions"

"$here/scripts/san-configure.sh" "$build"
# shellcheck disable=SC2046
cmake --build "$build" -j "$jobs" --target stex $(for a in $areas; do printf 'test_%s ' "$a"; done)

# UB fatal. Leak checking (LSan, suppressions for third-party process-lifetime state: lsan.supp says why) only
# with LEAK_CHECK=1: LSan's stop-the-world tracer itself crashes now and then at the exit of a process whose
# PoCL worker threads are being torn down ("Tracer caught signal 11 ... LeakSanitizer has encountered a fatal
# error", google/sanitizers#1353), which would make CI fail at random (docs/hardening.md).
export ASAN_OPTIONS="detect_leaks=${LEAK_CHECK:-0}:abort_on_error=0:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="suppressions=$supp/ubsan.supp:print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
# By label (an area's tests carry its name; analysis_clfft is labelled analysis, see tests/CMakeLists.txt).
labels="^($(echo $areas | tr ' ' '|'))\$"
cd "$build" && ctest --output-on-failure -j "$jobs" -L "$labels"
