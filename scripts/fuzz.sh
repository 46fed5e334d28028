#!/usr/bin/env bash
# Bounded libFuzzer runs (issue #12, docs/hardening.md): configures the shared clang sanitizer tree
# (scripts/san-configure.sh, default build-san: ASan + UBSan, the libraries the
# targets reach with fuzzer-no-link), builds the four targets of fuzz/ and runs each for
# FUZZ_SECONDS (default 60) on a scratch copy of its corpus (fuzz/corpus/<target>/ is only read: new inputs
# stay out of the repo). A crash writes its input to fuzz/regressions/<target>/ (add it to git after fixing)
# and makes this script exit 1. Usage: scripts/fuzz.sh [build-dir]   env: FUZZ_SECONDS, FUZZ_TARGETS, JOBS,
# FUZZ_JOBS (targets run at once, default JOBS).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-san}"
seconds="${FUZZ_SECONDS:-60}"
targets="${FUZZ_TARGETS:-model_file exemplar tile_spec name_template}"
jobs="${JOBS:-$(nproc)}"
"$here/scripts/san-configure.sh" "$build"
# shellcheck disable=SC2046
cmake --build "$build" -j "$jobs" --target $(for t in $targets; do printf 'fuzz_%s ' "$t"; done)

# Leaks inside OIIO/OpenEXR's process-wide caches are not findings here; ASan's leak check stays off.
export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
# One target per core at a time (FUZZ_JOBS, default JOBS): each still gets FUZZ_SECONDS of a whole core, and
# four targets take two minutes of wall clock on a 2-core CI machine instead of four.
fuzz_jobs="${FUZZ_JOBS:-$jobs}"
run_one() {
  local t="$1" scratch log
  scratch="$(mktemp -d)"
  cp -r "$here/fuzz/corpus/$t/." "$scratch/" 2>/dev/null || true
  mkdir -p "$here/fuzz/regressions/$t"
  log="$build/fuzz_$t.log"
  echo "fuzz.sh: $t for ${seconds}s"
  # -rss_limit_mb: OpenEXR may allocate ~800 MB inside open() for a tiny file (docs/hardening.md); 2.5 GB
  # keeps that legal and still catches runaway growth. -timeout: a single input taking 10 s is a hang.
  if ! nice -n 10 "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2560 \
       -max_len=65536 -artifact_prefix="$here/fuzz/regressions/$t/" -print_final_stats=1 "$scratch" > "$log" 2>&1; then
    echo "fuzz.sh: $t FOUND A CRASH (see $log and fuzz/regressions/$t/)" >&2
    tail -40 "$log" >&2
    rm -rf "$scratch"
    return 1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$log" | sed "s/^/  $t /" || true
  rm -rf "$scratch"
}
status=0
pids=()
for t in $targets; do
  run_one "$t" &
  pids+=("$!")
  if [ "${#pids[@]}" -ge "$fuzz_jobs" ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
