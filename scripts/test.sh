#!/usr/bin/env bash
# Build and run every test: a Release build with warnings as errors (all tests: unit, CLI,
# install), an x86-64-v3 build running the lane rows' tests (where the CPU has that level), an
# address + undefined sanitizer build running the unit tests, then a short libFuzzer run of
# every parser (scripts/fuzz.sh; skipped without clang).
# Usage: bash scripts/test.sh   (from the repository root; installs dependencies if missing)
set -euo pipefail
cd "$(dirname "$0")/.."

# Each phase's seconds go to the log, so that a slow CI shows where its time went.
phase() { echo "== scripts/test.sh: $1 done at $SECONDS s"; }

bash scripts/install-deps.sh
phase "dependencies"
jobs=$(nproc)
# ctest runs tests side by side, each with every core's worth of OpenMP threads: idle threads
# must sleep rather than spin, or they steal the cores the busy ones need (the solver tests run
# hundreds of short parallel regions per solve and slowed down 5-10x under spinning).
export OMP_WAIT_POLICY=PASSIVE

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPSTENCIL_WERROR=ON
cmake --build build -j "$jobs"
phase "Release build"
ctest --test-dir build --output-on-failure -j "$jobs"
phase "Release tests"

# The files compiled once per ISA level take blocks as wide as the level's vectors
# (src/core/lanes_level.h): the Release tests above run this CPU's level (blocks of 8 with
# AVX-512), the sanitizer build below blocks of 2. Where the CPU has x86-64-v3, a build for that
# level alone runs, in blocks of 4, the tests that hold the lane rows to the stored apply and
# the half list, the kept derivatives to the computed ones, and the flatness check (about 3 min).
printf 'int main(void) { __builtin_cpu_init(); return !__builtin_cpu_supports("x86-64-v3"); }\n' \
  > build/has_v3.c
if cc build/has_v3.c -o build/has_v3 && build/has_v3; then
  lane_tests="test_lanes test_half test_qsfdi test_lsmps test_lv test_periodic test_contract"
  cmake -S . -B build-v3 -DCMAKE_BUILD_TYPE=Release -DPSTENCIL_WERROR=ON -DPSTENCIL_BUILD_BENCH=OFF \
    -DPSTENCIL_ISA_DISPATCH=OFF -DCMAKE_C_FLAGS=-march=x86-64-v3 -DCMAKE_CXX_FLAGS=-march=x86-64-v3
  cmake --build build-v3 -j "$jobs" --target $lane_tests
  ctest --test-dir build-v3 --output-on-failure -j "$jobs" -R "^(${lane_tests// /|})\$"
  phase "x86-64-v3 lane tests"
else
  echo "== scripts/test.sh: this CPU has no x86-64-v3: the lane rows' blocks of 4 are not run"
fi

# One code path per kernel (generic x86-64): the ISA clones are the same source, and their
# three instrumented copies took 5 of the build's 8 minutes (docs/building.md). The Release
# tests above run the dispatched clones.
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Sanitize -DPSTENCIL_WERROR=ON -DPSTENCIL_BUILD_BENCH=OFF \
  -DPSTENCIL_ISA_DISPATCH=OFF
cmake --build build-sanitize -j "$jobs"
phase "sanitizer build"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:fast_unwind_on_malloc=0:print_suppressions=0" \
  ctest --test-dir build-sanitize --output-on-failure -L unit -j "$jobs"
phase "sanitizer tests"

# About 30 s per parser (PSTENCIL_FUZZ_SECONDS to change it); skipped cleanly without clang.
bash scripts/fuzz.sh
phase "fuzzing"
