#!/usr/bin/env bash
# Distributed solves (docs/distributed.md): `mpirun -n 2 pstencil run SCENE` gives the answer of
# `pstencil run SCENE` (one process, pstencil's own GMRES + AMG) to 1e-10 relative, for qsfdi,
# lv and lsmps on the 2D and 3D scenes of tests/ranks/, Dirichlet, mixed Neumann and periodic
# without Dirichlet particles (the mean of u fixed), solved to
# rtol 1e-13 (2D) and 1e-14 (3D); so does one process solving in PETSc (--petsc); so do schemes
# whose rows read two and three rings of neighbours (the CSPM family, mixed1, mixed0) over two
# ranks; 1 and 2 threads per rank give the same bits; the plan is one rank's; bad requests are
# refused.
# Usage: test_ranks.sh PATH_TO_PSTENCIL MPIEXEC
set -u
exe=$1
mpiexec=$2
scenes=$(cd "$(dirname "$0")/ranks" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root without these, and two ranks may exceed a container's slots; one
# thread per rank
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMP_NUM_THREADS=1
passed=0
failed=0

# The largest |a - b| over the largest |a| of column u of two CSV files, compared with 1e-10.
agree() {
  local what=$1 a=$2 b=$3
  local rel
  rel=$(awk -F, 'FNR == 1 { for (k = 1; k <= NF; ++k) if ($k == "u") c = k; next }
                 NR == FNR { u[FNR] = $c; m = (($c < 0 ? -$c : $c) > m) ? ($c < 0 ? -$c : $c) : m; n = FNR; next }
                 { d = $c - u[FNR]; d = d < 0 ? -d : d; if (d > w) w = d; k2 = FNR }
                 END { if (k2 != n || m == 0) print "mismatch"; else printf "%.3e", w / m }' "$a" "$b")
  if [ "$rel" != "mismatch" ] && awk -v r="$rel" 'BEGIN { exit !(r <= 1e-10) }'; then
    passed=$((passed + 1))
    echo "ok: $what: $rel"
  else
    failed=$((failed + 1))
    echo "FAIL: $what: relative difference $rel (limit 1e-10)"
  fi
}

# run OUT.csv DESCRIPTION -- COMMAND...: must exit 0
run() {
  local out=$1 what=$2
  shift 3
  if "$@" > "$work/log" 2>&1 && [ -s "$out" ]; then
    return 0
  fi
  failed=$((failed + 1))
  echo "FAIL: $what did not run"
  sed 's/^/  | /' "$work/log" | tail -20
  return 1
}

for scene in dirichlet_2d neumann_2d dirichlet_3d neumann_3d periodic_2d; do
  for scheme in qsfdi lv lsmps; do
    case=$scene/$scheme
    one=$work/one.csv two=$work/two.csv pet=$work/petsc.csv
    rm -f "$one" "$two" "$pet"
    run "$one" "$case, one process" -- "$exe" --quiet run "$scenes/$scene.json" \
      "operator.scheme=$scheme" "outputs.csv=$one" || continue
    run "$two" "$case, two ranks" -- "$mpiexec" -n 2 "$exe" --quiet run "$scenes/$scene.json" \
      "operator.scheme=$scheme" "outputs.csv=$two" && agree "$case: two ranks" "$one" "$two"
    run "$pet" "$case, one process in PETSc" -- "$exe" --quiet run "$scenes/$scene.json" \
      "operator.scheme=$scheme" "outputs.csv=$pet" --petsc "-ksp_gmres_restart 60" &&
      agree "$case: one process in PETSc" "$one" "$pet"
  done
done

# the rows of the CSPM family (the neighbours' volumes) and of the mixed schemes (the
# neighbours' gradients; mixed0's weigh by volumes of the ring past them) read two and three
# rings: the parts hold as many rings of ghosts (pst_scheme_halo). cspm and icspm at their
# stable setting, h = 0.9 s0 and K = 0.2 (docs/schemes/icspm.md); the mixed schemes with
# their own matrix for AMG, with which they converge (docs/distributed.md).
for pair in "icspm dirichlet_2d cloud.h_ratio=0.9 cloud.jitter=0.2" \
            "cspm dirichlet_2d cloud.h_ratio=0.9 cloud.jitter=0.2" \
            "csph2g neumann_3d" \
            "mixed0 dirichlet_2d tasks.0.amg_source=own" \
            "mixed1 neumann_2d tasks.0.amg_source=own"; do
  set -- $pair
  scheme=$1 scene=$2
  shift 2
  one=$work/one.csv two=$work/two.csv
  rm -f "$one" "$two"
  run "$one" "$scene/$scheme, one process" -- "$exe" --quiet run "$scenes/$scene.json" \
    "operator.scheme=$scheme" "$@" "outputs.csv=$one" || continue
  run "$two" "$scene/$scheme, two ranks" -- "$mpiexec" -n 2 "$exe" --quiet run \
    "$scenes/$scene.json" "operator.scheme=$scheme" "$@" "outputs.csv=$two" &&
    agree "$scene/$scheme${*:+ ($*)}: two ranks" "$one" "$two"
done

# PETSc's own choices through the command line and the scene key, which the command line
# overrides: the same answer, and the summary names what ran
one=$work/one.csv
"$exe" --quiet run "$scenes/dirichlet_3d.json" "outputs.csv=$one" > /dev/null 2>&1
# petsc_case WANT ARGS...: converged with "PETSc WANT" in the summary, and the same answer
petsc_case() {
  local want=$1
  shift
  rm -f "$work/p.csv"
  if "$exe" run "$scenes/dirichlet_3d.json" "outputs.csv=$work/p.csv" "$@" > "$work/log" 2>&1 &&
     grep -q "PETSc $want: CONVERGED" "$work/log"; then
    agree "dirichlet_3d/qsfdi with $*" "$one" "$work/p.csv"
  else
    failed=$((failed + 1))
    echo "FAIL: dirichlet_3d/qsfdi with $*: no 'PETSc $want: CONVERGED'"
    sed 's/^/  | /' "$work/log" | tail -8
  fi
}
petsc_case "gmres + ilu" --petsc "-pc_type ilu"
petsc_case "bcgs + jacobi" "tasks.0.petsc=-ksp_type bcgs -pc_type jacobi"
petsc_case "gmres + ilu" "tasks.0.petsc=-pc_type jacobi" --petsc "-pc_type ilu"
# GAMG (PETSc's AMG without hypre) smooths on the proxy, not on the scheme's rows
petsc_case "gmres + gamg" --petsc "-pc_type gamg"
# the options of the objects a PC makes in its set-up reach them (GAMG's levels)
if "$exe" run "$scenes/dirichlet_3d.json" "outputs={}" \
     --petsc "-pc_type gamg -mg_levels_pc_type sor -ksp_view" > "$work/log" 2>&1 &&
   grep -A1 "PC Object: (mg_levels_1_)" "$work/log" | grep -q "type: sor"; then
  passed=$((passed + 1))
else
  failed=$((failed + 1))
  echo "FAIL: -mg_levels_pc_type sor did not reach GAMG's smoother"
fi
# a fixed mean (periodic, no Dirichlet particle): GAMG's coarse solver relaxes, as BoomerAMG's
one=$work/one.csv
"$exe" --quiet run "$scenes/periodic_2d.json" "outputs.csv=$one" > /dev/null 2>&1
rm -f "$work/p.csv"
if "$exe" run "$scenes/periodic_2d.json" "outputs.csv=$work/p.csv" --petsc "-pc_type gamg" \
     > "$work/log" 2>&1 && grep -q "PETSc gmres + gamg: CONVERGED" "$work/log"; then
  agree "periodic_2d/qsfdi with --petsc -pc_type gamg" "$one" "$work/p.csv"
else
  failed=$((failed + 1))
  echo "FAIL: periodic_2d/qsfdi with --petsc -pc_type gamg: no 'PETSc gmres + gamg: CONVERGED'"
  sed 's/^/  | /' "$work/log" | tail -8
fi

# one and two threads per rank give the same bits (the applies and the part's operator are
# thread-count independent; PETSc and hypre are serial inside a rank)
for case in dirichlet_3d/qsfdi neumann_2d/lsmps; do
  scene=${case%/*} scheme=${case#*/}
  for t in 1 2; do
    OMP_NUM_THREADS=$t "$mpiexec" -n 2 "$exe" --quiet run "$scenes/$scene.json" \
      "operator.scheme=$scheme" "outputs.csv=$work/t$t.csv" > "$work/log" 2>&1
  done
  if [ -s "$work/t1.csv" ] && cmp -s "$work/t1.csv" "$work/t2.csv"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $case: two ranks with 1 and 2 threads each differ"
  fi
  rm -f "$work/t1.csv" "$work/t2.csv"
done

# the plan over two ranks: printed once, by rank 0; the run's report gives the plan's part
# beside rank 0's own (the estimated ghosts an upper estimate, docs/distributed.md)
"$mpiexec" -n 2 "$exe" run "$scenes/dirichlet_3d.json" --plan > "$work/log" 2>&1
if [ "$(grep -c '^plan for' "$work/log")" -eq 1 ] && grep -q '^  ranks      2 ' "$work/log"; then
  passed=$((passed + 1))
else
  failed=$((failed + 1))
  echo "FAIL: mpirun -n 2 run --plan: not one plan with its ranks line"
  sed 's/^/  | /' "$work/log" | tail -8
fi
"$mpiexec" -n 2 "$exe" --quiet run "$scenes/dirichlet_3d.json" "outputs={}" \
  "outputs.report=$work/r.json" > "$work/log" 2>&1
if python3 - "$work/r.json" <<'PY'; then
import json, sys
r = json.load(open(sys.argv[1]))
p, t = r["plan"], r["tasks"][0]["petsc"]
print(f"ok: plan's part {p['part_owned_estimate']} owned + {p['part_ghosts_estimate']} ghosts, "
      f"rank 0's {t['rank0_owned']} + {t['rank0_ghosts']}")
sys.exit(not (p["ranks"] == 2 and p["part_owned_estimate"] >= t["rank0_owned"] and
              t["rank0_ghosts"] <= p["part_ghosts_estimate"] <= 3 * t["rank0_ghosts"]))
PY
  passed=$((passed + 1))
else
  failed=$((failed + 1))
  echo "FAIL: two ranks: the plan's part against rank 0's"
fi

# refusals: a derivative task and another command over two ranks
refused() {
  local what=$1 code=$2 pattern=$3 rc
  shift 3
  "$@" > "$work/log" 2>&1
  rc=$?
  if [ $rc -eq "$code" ] && grep -q -- "$pattern" "$work/log"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $what: exit $rc, expected $code and '$pattern'"
    sed 's/^/  | /' "$work/log" | tail -8
  fi
}
refused "a gradient task over two ranks" 2 "only solve tasks run" "$mpiexec" -n 2 "$exe" \
  --quiet run "fields.f=x*y" 'tasks=[{"type":"gradient","field":"f"}]' cloud.spacing=0.1 \
  "outputs={}"
refused "a sweep over two ranks" 1 "only 'pstencil run' runs over" "$mpiexec" -n 2 "$exe" \
  sweep "$work/none.json"

echo "test_ranks: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
