#!/usr/bin/env bash
# Bounded libFuzzer runs (issue #12, docs/hardening.md): configures build-fuzz with clang, the whole library
# under -fsanitize=address,undefined,fuzzer-no-link, builds the four targets of fuzz/ and runs each for
# FUZZ_SECONDS (default 60) on a scratch copy of its corpus (fuzz/corpus/<target>/ is only read: new inputs
# stay out of the repo). A crash writes its input to fuzz/regressions/<target>/ (add it to git after fixing)
# and makes this script exit 1. Usage: scripts/fuzz.sh [build-dir]   env: FUZZ_SECONDS, FUZZ_TARGETS, JOBS.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-fuzz}"
seconds="${FUZZ_SECONDS:-60}"
targets="${FUZZ_TARGETS:-model_file exemplar tile_spec name_template}"
jobs="${JOBS:-$(nproc)}"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (scripts/install-deps.sh installs it)" >&2; exit 1; }

san="-fsanitize=address,undefined,fuzzer-no-link -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
cmake -S "$here" -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="$san" -DCMAKE_C_FLAGS="$san" -DSTEX_BUILD_FUZZERS=ON -DSTEX_BUILD_TESTS=OFF \
  -DSTEX_BUILD_BENCHMARKS=OFF -DSTEX_BUILD_PYTHON=OFF > "$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
# shellcheck disable=SC2086
cmake --build "$build" -j "$jobs" --target $(for t in $targets; do printf 'fuzz_%s ' "$t"; done)

# Leaks inside OIIO/OpenEXR's process-wide caches are not findings here; ASan's leak check stays off.
export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
status=0
for t in $targets; do
  scratch="$(mktemp -d)"
  cp -r "$here/fuzz/corpus/$t/." "$scratch/" 2>/dev/null || true
  mkdir -p "$here/fuzz/regressions/$t"
  log="$build/fuzz_$t.log"
  echo "fuzz.sh: $t for ${seconds}s"
  # -rss_limit_mb: OpenEXR may allocate ~800 MB inside open() for a tiny file (FIELD-NOTES); 2.5 GB keeps
  # that legal and still catches runaway growth. -timeout: a single input taking 10 s is a hang.
  if ! nice -n 10 "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2560 \
       -max_len=65536 -artifact_prefix="$here/fuzz/regressions/$t/" -print_final_stats=1 "$scratch" > "$log" 2>&1; then
    echo "fuzz.sh: $t FOUND A CRASH (see $log and fuzz/regressions/$t/)" >&2
    tail -40 "$log" >&2
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$log" | sed "s/^/  $t /" || true
  rm -rf "$scratch"
done
exit $status
