#!/usr/bin/env bash
# The hardening run (issue #12, docs/hardening.md "What CI runs"): one clang tree
# (scripts/san-configure.sh: ASan + UBSan + libFuzzer coverage hooks) serves both jobs:
#   1. the test areas of SANITIZE_AREAS under ASan + UBSan (scripts/sanitize.sh);
#   2. a bounded libFuzzer run of FUZZ_SECONDS per target (scripts/fuzz.sh).
# Prints the time of each phase. `make test` runs it after the normal suite (HARDENING=0 skips it). Usage: scripts/ci-hardening.sh [build-dir]
#   env: SANITIZE_AREAS (default below), FUZZ_SECONDS (default 30 here; 60 in `make fuzz`), FUZZ_TARGETS, JOBS.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-san}"
jobs="${JOBS:-$(nproc)}"
export SANITIZE_AREAS="${SANITIZE_AREAS:-runtime kernels analysis cli farm hardening surface gabor mix serve cs oiio}"
export FUZZ_SECONDS="${FUZZ_SECONDS:-30}"
export FUZZ_TARGETS="${FUZZ_TARGETS:-model_file exemplar tile_spec name_template}"
t0=$(date +%s)
"$here/scripts/san-configure.sh" "$build"
# One build invocation for everything both jobs need: the two cores stay busy across targets.
# shellcheck disable=SC2046
cmake --build "$build" -j "$jobs" --target stex $(for a in $SANITIZE_AREAS; do printf 'test_%s ' "$a"; done) \
  $(for t in $FUZZ_TARGETS; do printf 'fuzz_%s ' "$t"; done)
t1=$(date +%s)
"$here/scripts/sanitize.sh" "$build"
t2=$(date +%s)
"$here/scripts/fuzz.sh" "$build"
t3=$(date +%s)
echo "ci-hardening: sanitizer build $((t1 - t0)) s, sanitized tests ($SANITIZE_AREAS) $((t2 - t1)) s," \
     "fuzzing ($FUZZ_TARGETS) $((t3 - t2)) s, total $((t3 - t0)) s"
