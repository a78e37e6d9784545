#!/usr/bin/env bash
# Build and run every test: a Release build with warnings as errors (all tests: unit, CLI,
# install), then an address + undefined sanitizer build running the unit tests, then a short
# libFuzzer run of every parser (scripts/fuzz.sh; skipped without clang).
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

# One code path per kernel (generic x86-64): the ISA clones are the same source, and their
# three instrumented copies took 5 of the build's 8 minutes (docs/building.md). The Release
# tests above run the dispatched clones; this build also runs the lane rows in blocks of 2
# (kernels/lanes.h), where the Release build on an AVX-512 machine runs them in blocks of 8.
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
