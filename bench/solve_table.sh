#!/usr/bin/env bash
# Time to solution of the 10^6-particle Poisson problems (docs/solving.md, "Time to solution"):
# qsfdi, lpmps and lv in 2D and 3D, Jacobi and AMG, stored and matrix-free, one process per run
# (so each row's peak memory is its own). Prints a markdown table.
# usage: bench/solve_table.sh BUILD_DIR [DIMS] [JACOBI_MAX_ITER]     e.g. bench/solve_table.sh build "2 3" 1000
set -uo pipefail
build=${1:?usage: solve_table.sh BUILD_DIR [DIMS] [JACOBI_MAX_ITER]}
dims=${2:-"2 3"}
jacobi_max=${3:-1000}
export OMP_WAIT_POLICY=PASSIVE
bin="$build/bench/bench_solve"
"$bin" --header
for dim in $dims; do
  for scheme in qsfdi lpmps lv; do
    for precond in amg jacobi; do
      for stored in 1 0; do
        extra=()
        [ "$precond" = jacobi ] && extra=(--max-iter "$jacobi_max")
        # A run that does not converge exits 3 after printing its row: keep going.
        "$bin" --dim "$dim" --scheme "$scheme" --precond "$precond" --stored "$stored" "${extra[@]}" \
          || [ $? -eq 3 ] || echo "| ${dim}D | run failed: $scheme $precond stored=$stored |"
      done
    done
  done
done
