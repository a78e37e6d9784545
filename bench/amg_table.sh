#!/usr/bin/env bash
# The AMG settings table of docs/solving.md ("The AMG matrix"): GMRES + BoomerAMG on the
# manufactured Poisson problem of bench_solve (stored operator, rtol 1e-8) for qsfdi, lpmps,
# lsmps and lv in 2D and 3D at two sizes, over the proxy's radius (in h; 0 = the whole list),
# aggressive coarsening levels (on the Brookshaw proxy, also for lsmps, whose default is its own
# matrix) and, for qsfdi, the scheme's own matrix. One process per row,
# so each row's peak memory is its own. Prints a markdown table.
# usage: bench/amg_table.sh BUILD_DIR [DIMS] [SCHEMES]       e.g. bench/amg_table.sh build "2 3"
set -uo pipefail
build=${1:?usage: amg_table.sh BUILD_DIR [DIMS] [SCHEMES]}
dims=${2:-"2 3"}
schemes=${3:-"qsfdi lpmps lsmps lv"}
export OMP_WAIT_POLICY=PASSIVE
bin="$build/bench/bench_solve"
"$bin" --header
row() { "$bin" "$@" || [ $? -eq 3 ] || echo "| run failed: $* |"; }
for dim in $dims; do
  if [ "$dim" = 2 ]; then sizes="40000 160000"; else sizes="36000 130000"; fi
  for n in $sizes; do
    for scheme in $schemes; do
      for setting in "0 0" "1.3 0" "1.6 0" "2.0 0" "1.3 1"; do
        set -- $setting
        row --dim "$dim" --n "$n" --scheme "$scheme" --amg-source brookshaw --amg-radius "$1" \
          --amg-aggressive "$2" --max-iter 500
      done
      [ "$scheme" = qsfdi ] && row --dim "$dim" --n "$n" --scheme "$scheme" --amg-source own \
        --amg-aggressive 0 --max-iter 500
    done
  done
done
