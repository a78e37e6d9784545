#!/usr/bin/env bash
# The multicore scaling table (bench/README.md, "bench_scaling"): neighbours, precompute, stored
# and matrix-free apply, one AMG-preconditioned solve, at 1, 2, 4, 8 and 16 threads, as many of
# those as the machine has cores; medians of alternated repetitions, with speed-up and efficiency.
# Usage: bash bench/scaling.sh [BUILD_DIR] [extra bench_scaling options, e.g. --n 2000000]
# BUILD_DIR (default build) must have been configured with -DPSTENCIL_BUILD_BENCH=ON (the default).
# At 3D 10^6 on 2 cores the whole run took 3.5 minutes (bench/README.md); each further thread
# count adds its own share, less than the 1-thread one; 1..16 on a 16-core Xeon took 5.4 minutes.
set -euo pipefail
build=${1:-build}
shift || true
bin="$build/bench/bench_scaling"
[ -x "$bin" ] || { echo "scaling.sh: $bin not built (cmake --build $build --target bench_scaling)" >&2; exit 1; }

cores=$(nproc)
threads=""
for t in 1 2 4 8 16; do
  [ "$t" -le "$cores" ] && threads="${threads:+$threads,}$t"
done
[ "$cores" -lt 16 ] && echo "scaling.sh: $cores cores: thread counts $threads (16 needs a 16-core machine)"
# One thread per core, packed: the thread counts compare cores, not hyper-threads.
export OMP_PROC_BIND=close OMP_PLACES=cores
exec "$bin" --threads "$threads" "$@"
