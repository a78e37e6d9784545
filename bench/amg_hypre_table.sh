#!/usr/bin/env bash
# hypre's settings table of docs/solving.md ("hypre's coarsening and interpolation", "The AMG
# matrix per scheme"): bench_solve (GMRES + BoomerAMG, stored operator, rtol 1e-8) on the
# manufactured Poisson problem at two sizes per dimension. Part "qsfdi" varies one setting at a
# time around the library's defaults (coarsening, interpolation, P_max, strong threshold) and
# then the combinations listed in CHOSEN; part "schemes" runs lpmps, lsmps and lv with the
# defaults and with each combination of CHOSEN; part "source" runs qsfdi, lpmps, lsmps and lv on
# the Brookshaw proxy and on their own matrix, with the defaults; part "growth" runs qsfdi with
# the defaults and with classical interpolation at a third size (2D 640 000, 3D 500 000), where
# the two interpolations' iteration counts part. Every configuration runs PASSES times, passes
# outermost (the load of the machine spreads over all of them); the times are the medians, the
# iterations and entries do not depend on the load. One process per run, so each run's peak
# memory is its own.
# usage: bench/amg_hypre_table.sh BUILD_DIR [PARTS] [DIMS]
#        env CHOSEN="--amg-coarsen pmis;--amg-pmax 6" (';'-separated, default none),
#            PASSES (default 3)
set -uo pipefail
build=${1:?usage: amg_hypre_table.sh BUILD_DIR [PARTS] [DIMS]}
parts=${2:-"qsfdi schemes source"}
dims=${3:-"2 3"}
IFS=';' read -ra chosen <<< "${CHOSEN:-}"
passes=${PASSES:-3}
export OMP_WAIT_POLICY=PASSIVE
bin="$build/bench/bench_solve"

sizes() { if [ "$1" = 2 ]; then echo "40000 160000"; else echo "36000 130000"; fi; }
# The settings varied around the defaults, one at a time; "" is the defaults themselves.
variations() {
  echo ""
  echo "--amg-coarsen pmis"
  echo "--amg-coarsen falgout"
  echo "--amg-interp classical"
  for p in 0 2 6; do echo "--amg-pmax $p"; done
  if [ "$1" = 2 ]; then echo "--amg-strong 0.5"; else
    echo "--amg-strong 0.25"
    echo "--amg-strong 0.7"
  fi
}

configs=()   # "dim n scheme | settings"
for dim in $dims; do
  for n in $(sizes "$dim"); do
    for part in $parts; do
      case $part in
        qsfdi)
          while IFS= read -r v; do configs+=("$dim $n qsfdi|$v"); done < <(variations "$dim")
          for c in "${chosen[@]}"; do configs+=("$dim $n qsfdi|$c"); done ;;
        schemes)
          for s in lpmps lsmps lv; do
            configs+=("$dim $n $s|")
            for c in "${chosen[@]}"; do configs+=("$dim $n $s|$c"); done
          done ;;
        source)
          for s in qsfdi lpmps lsmps lv; do
            configs+=("$dim $n $s|--amg-source brookshaw")
            configs+=("$dim $n $s|--amg-source own")
          done ;;
      esac
    done
  done
  if [[ " $parts " == *" growth "* ]]; then
    if [ "$dim" = 2 ]; then n=640000; else n=500000; fi
    configs+=("$dim $n qsfdi|" "$dim $n qsfdi|--amg-interp classical")
  fi
done

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for ((p = 0; p < passes; ++p)); do
  for k in "${!configs[@]}"; do
    read -r dim n scheme <<< "${configs[k]%%|*}"
    # shellcheck disable=SC2086
    "$bin" --dim "$dim" --n "$n" --scheme "$scheme" --max-iter 500 ${configs[k]#*|} \
      >> "$out/$k" 2>/dev/null || [ $? -eq 3 ] || echo "| run failed |" >> "$out/$k"
  done
done

median() { sort -g | awk '{v[NR] = $1} END {print NR ? v[int((NR + 1) / 2)] : "-"}'; }
echo "| dim | particles | scheme | settings | iterations | set-up s | solve s | entries per row | set-up peak B/row |"
echo "|---|---|---|---|---|---|---|---|---|"
for k in "${!configs[@]}"; do
  settings=${configs[k]#*|}
  # bench_solve's columns: 2 dim, 3 particles, 5 scheme, 11 set-up s, 12 solve s,
  # 13 iterations, 18 AMG nnz/row, 19 set-up peak B/row
  first=$(head -n 1 "$out/$k")
  setup=$(awk -F'|' '{print $11}' "$out/$k" | median)
  solve=$(awk -F'|' '{print $12}' "$out/$k" | median)
  peak=$(awk -F'|' '{print $19}' "$out/$k" | median)
  awk -F'|' -v s="${settings:-defaults}" -v a="$setup" -v b="$solve" -v m="$peak" \
    '{gsub(/ /, "", $13); printf "|%s|%s|%s| %s | %s | %s | %s |%s| %s |\n", $2, $3, $5, s, $13, a, b, $18, m}' \
    <<< "$first"
done
