#!/usr/bin/env bash
# Build the libFuzzer harnesses (tests/fuzz, docs/fuzzing.md) with clang and run each for a few
# seconds: first every committed seed and crash reproducer (ctest -L fuzz), then the short
# fuzzing run of the `fuzz` target. Skips (exit 0) with a message when clang or libFuzzer is
# missing. A non-zero exit status when a harness finds a crash; its input is in
# build-fuzz/fuzz-artifacts/.
# Usage: bash scripts/fuzz.sh [SECONDS]   (per harness; default $PSTENCIL_FUZZ_SECONDS or 30;
#        the compiler is $PSTENCIL_FUZZ_CC, default clang)
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-${PSTENCIL_FUZZ_SECONDS:-30}}
case $seconds in
  ''|*[!0-9]*) echo "fuzz.sh: SECONDS must be a whole number (got '$seconds')" >&2; exit 1 ;;
esac
cc=${PSTENCIL_FUZZ_CC:-clang}
if ! command -v "$cc" >/dev/null; then
  echo "fuzz.sh: $cc not found: fuzzing skipped" \
       "(Debian: apt-get install clang libclang-rt-dev libomp-dev)"
  exit 0
fi
probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT
cat > "$probe/probe.c" <<'EOF_PROBE'
#include <stddef.h>
#include <stdint.h>
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }
EOF_PROBE
if ! "$cc" -fsanitize=fuzzer,address,undefined "$probe/probe.c" -o "$probe/probe" 2>/dev/null; then
  echo "fuzz.sh: $cc cannot link with -fsanitize=fuzzer: fuzzing skipped" \
       "(Debian: apt-get install libclang-rt-dev)"
  exit 0
fi

jobs=$(nproc)
export OMP_WAIT_POLICY=PASSIVE
# Warnings are errors here too: clang warns about things gcc does not (operator precedence,
# implicit declarations that a glibc header lets through for gcc).
CC=$cc cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DPSTENCIL_FUZZ=ON -DPSTENCIL_WERROR=ON \
  -DPSTENCIL_FUZZ_SECONDS="$seconds" -DPSTENCIL_BUILD_TESTS=OFF -DPSTENCIL_BUILD_BENCH=OFF
cmake --build build-fuzz -j "$jobs"
UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir build-fuzz --output-on-failure -L fuzz -j "$jobs"
cmake --build build-fuzz --target fuzz -j "$jobs"
