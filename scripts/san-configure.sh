#!/usr/bin/env bash
# Configures the sanitizer tree shared by scripts/sanitize.sh and scripts/fuzz.sh (docs/hardening.md): clang,
# the whole library and the test binaries under -fsanitize=address,undefined (UB reports fatal), the libraries
# the fuzz targets reach also with fuzzer-no-link (libFuzzer's coverage hooks, STEX_FUZZ_COVERAGE in
# CMakeLists.txt; without libFuzzer linked they are the sanitizer runtime's no-op defaults), the libFuzzer
# targets of fuzz/ enabled. One tree, one build of the library for both jobs.
# Usage: scripts/san-configure.sh BUILD_DIR   (honours CMAKE_C_COMPILER_LAUNCHER / CMAKE_CXX_COMPILER_LAUNCHER
# from the environment, e.g. ccache). No -Werror here: clang's warnings differ from gcc's, and the warning
# gate is the normal build's.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:?usage: san-configure.sh BUILD_DIR}"
command -v clang++ >/dev/null || { echo "stex: clang++ not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
san="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
launch=()
[ -n "${CMAKE_CXX_COMPILER_LAUNCHER:-}" ] && launch+=("-DCMAKE_CXX_COMPILER_LAUNCHER=$CMAKE_CXX_COMPILER_LAUNCHER")
[ -n "${CMAKE_C_COMPILER_LAUNCHER:-}" ] && launch+=("-DCMAKE_C_COMPILER_LAUNCHER=$CMAKE_C_COMPILER_LAUNCHER")
# -O1: ASan's recommended level (-O2 adds compile time and little speed under ASan); -gline-tables-only: file:line
# in every report at a fraction of -g's compile and link time (measured, docs/hardening.md).
cmake -S "$here" -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Sanitize \
  -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_SANITIZE="-O1 -gline-tables-only" \
  -DCMAKE_CXX_FLAGS="$san" -DCMAKE_C_FLAGS="$san" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DSTEX_SANITIZE=ON -DSTEX_FUZZ_COVERAGE=ON -DSTEX_BUILD_FUZZERS=ON -DSTEX_BUILD_TESTS=ON -DSTEX_BUILD_BENCHMARKS=ON -DSTEX_BUILD_PYTHON=OFF \
  "${launch[@]}" > "$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
