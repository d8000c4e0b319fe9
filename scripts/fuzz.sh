#!/usr/bin/env bash
# Builds and runs the libFuzzer target cpp/fuzz/fuzz_section.cpp (slicer + section properties +
# a tiny analysis) with AddressSanitizer + UndefinedBehaviorSanitizer.
#
#   scripts/fuzz.sh              # full run: 1 000 000 inputs (~10-20 min on 2 cores)
#   scripts/fuzz.sh 20000        # CI smoke run (~30 s incl. build)
#   JOBS=2 scripts/fuzz.sh 0     # run until stopped (0 = no limit), 2 parallel workers
#
# Needs clang with libFuzzer (Debian: apt-get install clang libclang-rt-14-dev), cmake, Eigen.
# Corpus: build-fuzz/corpus (kept between runs); crashes: build-fuzz/crash-* (reproduce with
# build-fuzz/fuzz_section build-fuzz/crash-<hash>; FUZZ_DUMP=1 prints the decoded mesh/plane).
# Exit code non-zero when a crash was found.
set -euo pipefail
RUNS="${1:-1000000}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build-fuzz}"
CC="${CC:-clang}" CXX="${CXX:-clang++}" cmake -S "$ROOT" -B "$BUILD" -G "${GENERATOR:-Unix Makefiles}" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOSTEON_FUZZ=ON -DOSTEON_BUILD_TESTS=OFF \
  -DOSTEON_SANITIZE=ON -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" >/dev/null
cmake --build "$BUILD" --target fuzz_section -j "$(nproc)" >/dev/null
mkdir -p "$BUILD/corpus"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
cd "$BUILD"
ARGS=(-runs="$RUNS" -max_len=512 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1)
if [[ "${JOBS:-1}" -gt 1 ]]; then
  # Parallel workers split the runs between them.
  ARGS=(-runs="$((RUNS / JOBS))" -jobs="$JOBS" -workers="$JOBS" -max_len=512 -timeout=10
        -rss_limit_mb=2048 -print_final_stats=1)
fi
# cpp/fuzz/regressions: inputs that once failed (run first as seeds; new units go to corpus/).
exec ./fuzz_section "${ARGS[@]}" corpus "$ROOT/cpp/fuzz/regressions"
