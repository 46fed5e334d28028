#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build of the test suite (issue #12, docs/hardening.md):
# configures build-asan (gcc is fine) with -fsanitize=address,undefined -fno-omit-frame-pointer, UB reports
# fatal, builds the test binaries of SANITIZE_AREAS and runs them with ctest. Suppressions (LeakSanitizer
# only, for PoCL/LLVM/ICD internals) are in fuzz/sanitizer-suppressions/, each justified there.
# Usage: scripts/sanitize.sh [build-dir]   env: SANITIZE_AREAS (default: all areas), JOBS.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-asan}"
areas="${SANITIZE_AREAS:-runtime kernels analysis cli farm hardening}"
jobs="${JOBS:-$(nproc)}"
supp="$here/fuzz/sanitizer-suppressions"

san="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS="$san" -DCMAKE_C_FLAGS="$san" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DSTEX_BUILD_BENCHMARKS=OFF -DSTEX_BUILD_PYTHON=OFF > "$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
# shellcheck disable=SC2086
cmake --build "$build" -j "$jobs" --target stex $(for a in $areas; do printf 'test_%s ' "$a"; done)

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="suppressions=$supp/ubsan.supp:print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
regex="^($(echo $areas | tr ' ' '|'))\$"
cd "$build" && ctest --output-on-failure -j "$jobs" -R "$regex"
