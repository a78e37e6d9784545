#!/usr/bin/env bash
# Build and run every test: a Release build with warnings as errors (all tests: unit, CLI,
# install), then an address + undefined sanitizer build running the unit tests.
# Usage: bash scripts/test.sh   (from the repository root; installs dependencies if missing)
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
jobs=$(nproc)

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPSTENCIL_WERROR=ON
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure -j "$jobs"

cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Sanitize -DPSTENCIL_WERROR=ON -DPSTENCIL_BUILD_BENCH=OFF
cmake --build build-sanitize -j "$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-sanitize --output-on-failure -L unit -j "$jobs"
