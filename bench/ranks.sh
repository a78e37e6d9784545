#!/usr/bin/env bash
# One rank against several (docs/distributed.md, docs/scale.md): the same 3D qsfdi Poisson scene
# (scenes/large/poisson_3d_1e7.json cut to a cube of side SIDE) solved by
#   own      pstencil run, pstencil's GMRES + AMG, T threads
#   petsc    pstencil run --petsc "", one process in PETSc, T threads
#   petsc1   the same with one thread (the base of the ranks' efficiency)
#   ranks R  mpirun -n R pstencil run, one thread per rank, for each R of RANKS
# alternating the configurations REPS times; prints per run the wall time, the times of the
# neighbours (+ part) and precompute, the solve (set-up within it), the iterations, rank 0's
# peak resident memory, owned and ghost particles, and the error against the exact solution.
# Usage: bench/ranks.sh [PSTENCIL] [SIDE] [REPS] [RANKS] [T]
#   defaults: build/pstencil 0.8 (81^3 = 531441 particles) 2 "2" 2
set -euo pipefail
exe=${1:-build/pstencil}
side=${2:-0.8}
reps=${3:-2}
ranks=${4:-2}
threads=${5:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
scene=$here/scenes/large/poisson_3d_1e7.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
args=("cloud.hi=[$side,$side,$side]" "outputs.report=$work/report.json")

# one configuration: NAME COMMAND... ; appends a table row
row() {
  local name=$1
  shift
  local t0 t1
  t0=$(date +%s.%N)
  "$@" > "$work/log" 2>&1 || { echo "| $name | failed: $(tail -1 "$work/log") |"; return; }
  t1=$(date +%s.%N)
  python3 - "$work/report.json" "$name" "$t0" "$t1" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["tasks"][0]
s, p = t["solver"], t.get("petsc", {})
op = r["operators"][0]["phases"] if r.get("operators") else {}
pre = op.get("precompute", 0.0)
part = p.get("rank0_part_seconds")
nb = r["timers"].get("neighbours", 0.0)
ghosts = p.get("rank0_ghosts")
owned = p.get("rank0_owned")
print("| %s | %.1f | %s | %.2f | %.2f (%.2f) | %d | %.2f | %s | %.3e |" % (
    sys.argv[2], float(sys.argv[4]) - float(sys.argv[3]),
    "%.2f" % nb if part is None else "%.2f + part %.2f" % (nb, part), pre, t["seconds"],
    s.get("setup_seconds", 0.0), s["iterations"], r["peak_rss_bytes"] / 2**30,
    "-" if owned is None else "%d / %d (%.0f %%)" % (owned, ghosts, 100.0 * ghosts / owned),
    t["norms"]["rel_l2"]))
EOF
}

n=$(python3 -c "import math; k = round($side / 0.01) + 1; print(k ** 3)")
echo "3D qsfdi Poisson, $n particles (side $side), $(nproc) cores, $(date -u +%Y-%m-%dT%H:%MZ)"
echo
echo "| run | wall s | neighbours s | precompute s | solve s (set-up) | iterations | rank 0 peak GiB | rank 0 owned / ghosts | rel L2 |"
echo "|---|---|---|---|---|---|---|---|---|"
for rep in $(seq "$reps"); do
  row "own, $threads threads" env OMP_NUM_THREADS="$threads" "$exe" --quiet run "$scene" "${args[@]}"
  row "PETSc, 1 process, $threads threads" env OMP_NUM_THREADS="$threads" "$exe" --quiet run \
    "$scene" "${args[@]}" --petsc ""
  row "PETSc, 1 process, 1 thread" env OMP_NUM_THREADS=1 "$exe" --quiet run "$scene" \
    "${args[@]}" --petsc ""
  for r in $ranks; do
    row "PETSc, $r ranks x 1 thread" env OMP_NUM_THREADS=1 mpiexec -n "$r" "$exe" --quiet run \
      "$scene" "${args[@]}"
  done
done
