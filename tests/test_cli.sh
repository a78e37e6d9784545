#!/usr/bin/env bash
# The program's contract: exit codes (0 ok, 1 usage, 2 bad input), messages that name the
# problem, and statistics that match a cloud whose neighbour counts are known.
# Usage: test_cli.sh PATH_TO_PSTENCIL
set -u
exe=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

# expect CODE DESCRIPTION -- COMMAND...: run, compare the exit code, keep stdout/stderr.
expect() {
  local code=$1 what=$2
  shift 3
  "$@" > "$work/out" 2> "$work/err"
  local rc=$?
  if [ "$rc" -eq "$code" ]; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $what: exit $rc, expected $code"
    sed 's/^/  stderr: /' "$work/err"
  fi
}
# grep_out FILE PATTERN DESCRIPTION
contains() {
  if grep -q -- "$2" "$work/$1"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $3: '$2' not in $1"
    sed 's/^/  | /' "$work/$1"
  fi
}

# check DESCRIPTION SHELL-CONDITION
check() {
  if eval "$2"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $1"; fi
}
expect 0 "--help" -- "$exe" --help
contains out "exit codes" "help lists exit codes"
expect 0 "--version" -- "$exe" --version
contains out "pstencil 0\." "version string"
expect 1 "no command" -- "$exe"
expect 1 "unknown command" -- "$exe" frobnicate
contains err "unknown command 'frobnicate'" "unknown command named"
expect 1 "bad --threads" -- "$exe" --threads zero sysinfo
expect 1 "--threads 0" -- "$exe" --threads 0 sysinfo
expect 0 "sysinfo" -- "$exe" --threads 2 sysinfo
contains out "cores" "sysinfo prints cores"
contains out "OpenMP threads       2" "--threads reaches OpenMP"
contains out "L1 data cache\|L2 cache" "sysinfo prints caches"
# The program waits passively unless the user chose a policy (libgomp reads the variable
# before main, so the program executes itself again with it set; docs/cli.md).
expect 0 "sysinfo, no wait policy set" -- env -u OMP_WAIT_POLICY "$exe" sysinfo
contains out "wait policy          passive (default)" "passive waiting by default"
expect 0 "sysinfo, the user's wait policy" -- env OMP_WAIT_POLICY=active "$exe" sysinfo
contains out "wait policy          active (OMP_WAIT_POLICY)" "the user's wait policy wins"
expect 0 "libgomp sees the default policy" -- \
  env -u OMP_WAIT_POLICY OMP_DISPLAY_ENV=verbose "$exe" --version
contains err "GOMP_SPINCOUNT = '0'" "libgomp runs with no spinning"
expect 0 "libgomp sees the user's policy" -- \
  env OMP_WAIT_POLICY=active OMP_DISPLAY_ENV=verbose "$exe" --version
contains err "OMP_WAIT_POLICY = 'ACTIVE'" "libgomp runs the user's policy"
expect 1 "exit code through the re-exec" -- env -u OMP_WAIT_POLICY "$exe" frobnicate
contains err "unknown command 'frobnicate'" "arguments through the re-exec"

# cloud generation and its errors
expect 1 "cloud without -o" -- "$exe" cloud
expect 1 "cloud bad option" -- "$exe" cloud --s0 -1 -o "$work/x.csv"
contains err "option --s0" "bad --s0 named"
expect 1 "cloud unknown option" -- "$exe" cloud --frob -o "$work/x.csv"
expect 1 "cloud box not a whole number of spacings" -- "$exe" cloud --s0 0.3 -o "$work/x.csv"
[ ! -e "$work/x.csv" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: failed cloud left a file"; }
expect 2 "cloud into a missing directory" -- "$exe" cloud -o "$work/nodir/x.csv"
[ -z "$(ls -A "$work/nodir" 2>/dev/null)" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: partial file left"; }

# A 2D 11x11 lattice, s0 = 1/8, h = s0, cubic support 2h: interior particles have exactly the
# 8 lattice points closer than 2 s0, corners 3.
expect 0 "cloud 2D" -- "$exe" cloud --dim 2 --lo 0,0 --hi 1.25,1.25 --s0 0.125 --h-ratio 1 -o "$work/c2.csv"
contains out "wrote 121 particles" "cloud count"
head -n 1 "$work/c2.csv" > "$work/header"
contains header "^x,y,V,h,kind,nx,ny" "CSV header"
expect 0 "neighbours 2D cubic" -- "$exe" --threads 2 neighbours "$work/c2.csv" --kernel cubic
contains out "neighbours           min 3, mean" "min neighbours"
contains out "max 8, isolated 0" "max neighbours"
contains out "particles            121 (2D)" "particle count"

# Bad input files: exit 2 and the file:line:column in the message.
printf 'x,y,V,h,kind,nx,ny\n0,0,1,1,interior,0,0\n1,nan,1,1,interior,0,0\n' > "$work/nan.csv"
expect 2 "NaN in a cloud" -- "$exe" neighbours "$work/nan.csv"
contains err "nan.csv:3:2" "NaN located at line 3 column 2"
printf 'x,y,V,h,kind,nx,ny\n0,0,1,1,interior,0,0\n0,0,1,1,interior,0,0\n' > "$work/dup.csv"
expect 2 "duplicate particles" -- "$exe" neighbours "$work/dup.csv"
contains err "dup.csv" "duplicate message names the file"
expect 2 "missing file" -- "$exe" neighbours "$work/none.csv"
expect 1 "neighbours without file" -- "$exe" neighbours
expect 1 "neighbours bad kernel" -- "$exe" neighbours "$work/c2.csv" --kernel gauss

# The main job on a small version of the default scene.
# run: the built-in scene (coarsened by an override), plans, scene files, outputs, refusals
scenes="$(cd "$(dirname "$0")/../scenes" && pwd)"
expect 0 "run (built-in scene, small)" -- "$exe" run cloud.spacing=0.05
contains out "9261 particles" "run particle count (21^3)"
contains out "task laplacian (laplacian), rel_l2" "run reports the Laplacian's error"
contains out "task gradient (gradient), rel_l2" "run reports the gradient's error"
# Progress lines (docs/cli.md, "Progress"): none when stderr is not a terminal, unless
# --progress asks; then whole lines, one at the end of each phase and task, fitted to $COLUMNS.
check "no progress lines on a pipe without --progress" \
  '! grep -q "neighbours\|precompute\|rows/s" "$work/err"'
expect 0 "run --progress on a pipe" -- env COLUMNS=60 "$exe" --progress run cloud.spacing=0.05
contains err "^neighbours \[#*\] 100% [0-9.]* s [0-9.e]* rows/s$" "the neighbours' progress line"
contains err "^precompute \[#*\] 100% [0-9.]* s [0-9.e]* rows/s$" "the precompute's progress line"
contains err "^task gradient \[#*\] 100% [0-9.]* s [0-9.e]* rows/s$" "a task's progress line"
contains err "^task laplacian [0-9.]* s$" "an apply task's line has the clock only"
check "progress lines fit in COLUMNS - 1" '! awk "length > 59" "$work/err" | grep -q .'
check "a log gets no carriage returns or escapes" '! grep -q "$(printf "\r\|\033")" "$work/err"'
expect 0 "--progress under --quiet" -- "$exe" --quiet --progress run cloud.spacing=0.05
check "--quiet wins over --progress" '[ ! -s "$work/out" ] && [ ! -s "$work/err" ]'
expect 0 "run --help" -- "$exe" run --help
expect 0 "run --plan" -- "$exe" run --plan
contains out "1030301 particles" "plan of the built-in scene"
contains out "memory     about" "plan prints the memory estimate"
# under mpirun (its environment) the plan is one rank's, printed once, without starting MPI
ranks_env=(env OMPI_COMM_WORLD_SIZE=4 OMPI_COMM_WORLD_LOCAL_SIZE=2)
if "$exe" sysinfo | grep -q "^PETSc *not built in"; then
  # a build without PETSc refuses the solves the plan would put in PETSc, before any work
  expect 1 "run --plan over 4 ranks without PETSc" -- "${ranks_env[@]}" OMPI_COMM_WORLD_RANK=0 \
    "$exe" run "$scenes/large/poisson_3d_1e7.json" "cloud.hi=[0.3,0.3,0.3]" --plan
  contains err "solves in PETSc (over mpirun's ranks), but this pstencil was built without it" \
    "the plan refuses ranks without PETSc"
  expect 1 "run --petsc --plan without PETSc" -- "$exe" run "$scenes/qsfdi_test_c.json" \
    --petsc "-ksp_type gmres" --plan
  contains err "solves in PETSc (--petsc), but this pstencil was built without it" \
    "the plan refuses --petsc without PETSc"
else
  expect 0 "run --plan over 4 ranks, rank 0" -- "${ranks_env[@]}" OMPI_COMM_WORLD_RANK=0 "$exe" \
    run "$scenes/large/poisson_3d_1e7.json" "cloud.hi=[0.3,0.3,0.3]" --plan
  contains out "ranks      4 (2 on this node)" "the plan names the ranks"
  contains out "owned and [0-9]* ghost particles (estimated)" "the plan gives a rank's part"
  contains out "in PETSc over 4 ranks" "a solve over ranks runs in PETSc"
  contains out "available to the 2 ranks on this node" "the node's ranks share its memory"
  expect 0 "run --plan over 4 ranks, rank 3" -- "${ranks_env[@]}" OMPI_COMM_WORLD_RANK=3 "$exe" \
    run "$scenes/large/poisson_3d_1e7.json" "cloud.hi=[0.3,0.3,0.3]" --plan
  check "the other ranks print no plan" '[ ! -s "$work/out" ]'
fi
expect 2 "run --plan over 2 ranks: a task that does not run over ranks" -- \
  env OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 "$exe" run --plan
contains err "only solve tasks run" "the plan refuses what the run would"
expect 0 "help scene" -- "$exe" help scene
contains out "cloud.spacing" "help scene lists the keys"
expect 0 "run a scene file with outputs" -- "$exe" --quiet run "$scenes/qsfdi_test_c.json" \
  cloud.spacing=0.05 "outputs.csv=$work/c.csv" "outputs.vtu=$work/c.vtu" \
  "outputs.report=$work/c.json"
check "--quiet run prints nothing" '[ ! -s "$work/out" ]'
check "run wrote the CSV (441 rows + header)" '[ "$(wc -l < "$work/c.csv")" -eq 442 ]'
check "run wrote the VTU" 'grep -q "<VTKFile type=\"UnstructuredGrid\"" "$work/c.vtu"'
check "the report is JSON with counters, plan and solver" \
  "python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); assert r[\"counters\"][\"solves\"]==1 and r[\"tasks\"][0][\"solver\"][\"converged\"] and r[\"plan\"][\"particles\"]==441' '$work/c.json'"
# A scene on a VTU cloud (the one just written) with interpolation at the points of a CSV.
printf 'id,x,y\n0,0.3,0.4\n1,0.5,0.5\n' > "$work/pts.csv"
cat > "$work/vtu_scene.json" <<EOF
{ "dim": 2, "cloud": { "source": "file", "file": "c.vtu", "spacing": 0.05, "h_ratio": 1.2 },
  "fields": { "w": "x*x + y*y" },
  "tasks": [ { "type": "laplacian", "field": "w", "exact": "4", "norms": ["max_abs"] },
             { "type": "interpolate", "name": "at", "field": "w", "points": { "file": "pts.csv" },
               "exact": "x*x + y*y", "norms": ["max_abs"] } ],
  "outputs": { "csv": "$work/vtu_out.csv" } }
EOF
expect 0 "run a scene on a VTU cloud with CSV points" -- "$exe" run "$work/vtu_scene.json"
contains out "441 particles" "the VTU cloud has the written particles"
check "interpolation values written beside outputs.csv" '[ "$(wc -l < "$work/vtu_out_at.csv")" -eq 3 ]'
printf 'x,y\n0.3,abc\n' > "$work/pts.csv"
expect 2 "run: a bad points file" -- "$exe" run "$work/vtu_scene.json"
contains err "pts.csv:2: column y" "the points error names file, line and column"
expect 3 "run: a solve that does not converge" -- "$exe" run "$scenes/qsfdi_test_c.json" \
  cloud.spacing=0.05 tasks.0.max_iter=2 "outputs.report=$work/c2.json" "outputs.vtu=$work/c2.vtu"
contains err "iteration limit" "run says why the solve failed"
check "a failed solve still writes its report" '[ -s "$work/c2.json" ]'
# Every example scene plans; the small ones run (outputs land in $work).
for f in "$scenes"/*.json; do
  expect 0 "run --plan $(basename "$f")" -- "$exe" run "$f" --plan
done
for f in qsfdi_test_a lv_table2 lv_mixed heat_3d_divergence spe10_layer85 qsfdi_interpolate; do
  expect 0 "run scenes/$f.json" -- sh -c "cd '$work' && '$(readlink -f "$exe")' run '$scenes/$f.json'"
done
contains out "rows: none (derivatives only)" "interpolation and Hessian need no Laplacian rows"
expect 0 "run scenes/periodic_poisson_2d.json" -- \
  sh -c "cd '$work' && '$(readlink -f "$exe")' run '$scenes/periodic_poisson_2d.json'"
# The periodic example: no boundary, so the mean of u is fixed and the exact solution (mean 2)
# moved to u's mean 0; the error is then the discretisation's.
contains out "mean of u fixed (periodic, no Dirichlet particle), lambda" "the fixed mean is said"
check "periodic example: GMRES, lambda small, exact shifted by about -2, rel_l2 < 1e-2" \
  "python3 -c 'import json,sys; t=json.load(open(sys.argv[1]))[\"tasks\"][0]; s=t[\"solver\"]; assert s[\"fix_mean\"] and s[\"method\"]==\"gmres\" and abs(s[\"mean_shift\"])<0.05 and abs(t[\"exact_shift\"]+2)<1e-2 and t[\"norms\"][\"rel_l2\"]<1e-2, t' '$work/periodic_poisson_2d.report.json'"
expect 0 "run scenes/heat_steps_2d.json" -- \
  sh -c "cd '$work' && '$(readlink -f "$exe")' run '$scenes/heat_steps_2d.json'"
contains out "explicit: 379 steps of dt 0.0001319 (limit)" "forward Euler reports its step"
contains out "implicit: 20 steps of dt 0.0025 (scene)" "backward Euler reports its steps"
check "the time series and the table are written" \
  '[ -s "$work/heat_explicit.pvd" ] && [ -s "$work/heat_explicit_000379.vtu" ] &&
   [ "$(wc -l < "$work/heat_implicit_steps.csv")" -eq 21 ]'
expect 2 "run: an explicit dt above the step limit" -- "$exe" run "$scenes/heat_steps_2d.json" \
  tasks.0.dt=0.001
contains err "exceeds the forward-Euler step limit" "the refusal gives the limit"
expect 0 "run scenes/lv_patch_2d.json" -- "$exe" run "$scenes/lv_patch_2d.json"
contains out "max_abs [0-9.]*e-1[1-6]" "the heterogeneous patch test holds to rounding"
expect 2 "run: missing scene file" -- "$exe" run "$work/none.json"
expect 2 "run: unknown key" -- "$exe" run cloud.jiter=0.3
contains err "did you mean 'cloud.jitter'" "run suggests the key"
expect 1 "run: unknown option" -- "$exe" run --bogus
expect 4 "run: a plan that does not fit is refused" -- "$exe" run cloud.spacing=0.0005
contains err "GB available" "the refusal gives the estimate"

# sweep: a scene over a grid of key values, a CSV row per (run, task), a summary, --resume
cat > "$work/sw.json" <<SWEEP
{ "scene": { "dim": 2,
    "cloud": { "source": "lattice", "spacing": 0.1, "jitter": 0.2, "boundary_layer": true },
    "fields": { "u": "sin(6*x + 8*y)" },
    "tasks": [ { "type": "laplacian", "field": "u", "exact": "-100*sin(6*x + 8*y)" } ] },
  "grid": { "operator.scheme": ["qsfdi", "lpmps"], "cloud.spacing": [0.1, 0.05],
            "cloud.seed": { "from": 1, "count": 2 } },
  "output": { "csv": "$work/sw.csv", "summary": "$work/sw.summary.json" } }
SWEEP
expect 0 "sweep" -- "$exe" sweep "$work/sw.json"
contains out "8 combinations, 8 run" "sweep counts its runs"
check "sweep CSV: header + 8 rows" '[ "$(wc -l < "$work/sw.csv")" -eq 9 ]'
check "sweep CSV header" \
  '[ "$(head -n 1 "$work/sw.csv" | cut -d, -f1-5)" = "operator.scheme,cloud.spacing,cloud.seed,dim,particles" ]'
check "sweep summary: groups, fits, machine" \
  "python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); assert len(s[\"groups\"])==4 and len(s[\"fits\"])==4 and s[\"machine\"][\"cores\"]>=1' '$work/sw.summary.json'"
# runs at once: the same CSV one at a time and two at a time, but for times, CPU and RSS
cp "$work/sw.csv" "$work/sw_default.csv"
expect 0 "sweep --jobs 2" -- "$exe" sweep "$work/sw.json" --jobs 2
contains out "8 of them small, run up to 2 at once in worker processes" "sweep --jobs 2 uses workers"
cp "$work/sw.csv" "$work/sw_jobs2.csv"
expect 0 "sweep --jobs 1" -- "$exe" sweep "$work/sw.json" --jobs 1
check "sweep --jobs 1 and 2: the same CSV but for times, CPU and RSS" \
  "python3 -c 'import csv,sys; a,b=[list(csv.reader(open(f))) for f in sys.argv[1:]]
t=lambda h: h.startswith(\"t_\") or h in (\"cpu\",\"peak_rss_bytes\")
assert len(a)==len(b)==9 and a[0]==b[0]
assert all(x==y for r,s in zip(a,b) for h,x,y in zip(a[0],r,s) if not t(h))' '$work/sw.csv' '$work/sw_jobs2.csv'"
expect 1 "sweep --jobs 0" -- "$exe" sweep "$work/sw.json" --jobs 0
contains err "--jobs needs an integer from 1 to 256" "sweep --jobs checked"
expect 2 "a sweep worker of another sweep" -- "$exe" sweep "$work/sw.json" --worker 0123456789abcdef
contains err "is not the sweep this worker was started for" "the worker checks the sweep's digest"
cp "$work/sw.csv" "$work/sw_before.csv"
expect 0 "sweep --resume" -- "$exe" sweep "$work/sw.json" --resume
contains out "0 run, 8 kept" "sweep --resume reruns nothing"
check "sweep --resume keeps the CSV bytes" 'cmp -s "$work/sw.csv" "$work/sw_before.csv"'
# plot: PNGs of the sweep just made (gnuplot-nox); each starts with the PNG signature and an
# IHDR of the requested size; nothing but the PNGs is left in the folder
expect 0 "plot" -- "$exe" plot "$work/sw.csv" --out "$work/plots" --size 640x400
contains out "wrote $work/plots/error_vs_s0.png" "plot writes error_vs_s0.png"
contains out "skipped time_ratio_vs_jitter.png: cloud.jitter is not a grid key" "plot says why it skips"
check "plot: 3 PNGs and no other file" '[ "$(ls -A "$work/plots" | grep -cv "\.png$")" -eq 0 ] &&
  [ "$(ls "$work/plots"/*.png | wc -l)" -eq 3 ]'
for f in "$work"/plots/*.png; do
  check "$(basename "$f"): PNG signature" \
    '[ "$(od -An -tx1 -N8 "$f" | tr -d " \n")" = "89504e470d0a1a0a" ]'
  check "$(basename "$f"): IHDR 640x400" \
    '[ "$(od -An -tx1 -j12 -N12 "$f" | tr -d " \n")" = "494844520000028000000190" ]'
done
expect 0 "plot: default folder <stem>_plots" -- "$exe" --quiet plot "$work/sw.csv"
check "plot: default folder" '[ -s "$work/sw_plots/phases.png" ]'
expect 2 "plot: missing file" -- "$exe" plot "$work/none.csv"
expect 1 "plot: unknown norm" -- "$exe" plot "$work/sw.csv" --norm l2
expect 1 "plot without a file" -- "$exe" plot
expect 2 "plot without gnuplot" -- env PATH=/nonexistent "$exe" plot "$work/sw.csv" --out "$work/p2"
contains err "gnuplot not found: install gnuplot-nox" "plot names the missing package"
# brookshaw has no gradient: its 4 runs fail, the sweep goes on, exit 16 + 4
sed -e 's/"lpmps"\]/"lpmps", "brookshaw"]/' -e 's/"type": "laplacian"/"type": "gradient"/' \
  -e 's/"exact": "-100\*sin(6\*x + 8\*y)"/"exact": ["6*cos(6*x+8*y)", "8*cos(6*x+8*y)"]/' \
  "$work/sw.json" > "$work/swf.json"
expect 20 "sweep: 4 failed runs (exit 16 + 4)" -- "$exe" --quiet sweep "$work/swf.json"
contains err "4 of 12 runs failed" "sweep says how many runs failed"
check "failed rows in the CSV" '[ "$(grep -c ",failed," "$work/sw.csv")" -eq 4 ]'
# output.pvd: each run writes STEM_runK.vtu, the .pvd lists those that ran (not the failed ones)
sed 's|"summary": "[^"]*"|&, "pvd": "'"$work"'/swp.pvd"|' "$work/swf.json" > "$work/swp.json"
expect 20 "sweep with output.pvd" -- "$exe" --quiet sweep "$work/swp.json"
check "the .pvd lists the 8 runs that did not fail, each file there" \
  "python3 -c 'import os,sys,xml.etree.ElementTree as E
d=E.parse(sys.argv[1]).getroot().find(\"Collection\").findall(\"DataSet\")
assert len(d)==8 and all(os.path.exists(os.path.join(os.path.dirname(sys.argv[1]),x.get(\"file\"))) for x in d)
assert [x.get(\"file\") for x in d][0]==\"swp_run0.vtu\"' '$work/swp.pvd'"
check "no VTU of a failed run" '[ ! -e "$work/swp_run8.vtu" ] && [ -s "$work/swp_run0.vtu" ]'
sed 's|swp.pvd|swp.vtu|' "$work/swp.json" > "$work/swpbad.json"
expect 2 "sweep: output.pvd must be a .pvd" -- "$exe" --quiet sweep "$work/swpbad.json"
contains err "expected a file name ending in .pvd" "the .pvd name checked"
sed 's/"cloud.seed"/"cloud.sed"/' "$work/sw.json" > "$work/swbad.json"
expect 2 "sweep: bad key" -- "$exe" sweep "$work/swbad.json"
contains err "swbad.json:6:13: key 'grid.cloud.sed': unknown scene key" "sweep names the bad key"
expect 2 "sweep: missing file" -- "$exe" sweep "$work/none.json"
expect 1 "sweep without a file" -- "$exe" sweep
expect 0 "sweep --help" -- "$exe" sweep --help
for f in "$scenes"/sweeps/*.json; do
  expect 0 "sweep --plan $(basename "$f")" -- "$exe" --quiet sweep "$f" --plan
done

# apply and stencil on a 21x21 lattice on [0,2]^2 (s0 = 0.1, h = 1.2 s0, all interior) with a
# field u = x^2 + y^2, so that Lu = 4 away from the boundary, and a mobility column k = 1 + x. The centre particle (1,1) is id 220
# (x runs fastest), a whole 1.0 from the box: beyond any kernel's reach (3h = 0.36).
# check NAME CONDITION: count a shell test.
expect 0 "cloud for apply" -- "$exe" cloud --dim 2 --lo 0,0 --hi 2,2 --s0 0.1 -o "$work/a.csv"
awk -F, 'NR == 1 { print $0 ",u,k"; next }
  { printf "%s,%.17g,%.17g\n", $0, $1 * $1 + $2 * $2, 1 + $1 }' \
  "$work/a.csv" > "$work/au.csv"
expect 0 "apply lv" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u --out "$work/lu.csv"
contains out "particles            441 (2D)" "apply particle count"
contains out "row status           ok" "apply prints status counts"
contains out "time apply" "apply prints timings"
check "apply writes particles + 1 rows" '[ "$(wc -l < "$work/lu.csv")" -eq 442 ]'
check "apply header" '[ "$(head -n 1 "$work/lu.csv")" = "id,Lu,Au,status" ]'
check "apply rows in input order" \
  '[ "$(awk -F, "NR > 1 && \$1 != NR - 2" "$work/lu.csv" | wc -l)" -eq 0 ]'
check "apply status names known" '[ "$(awk -F, "NR > 1" "$work/lu.csv" | cut -d, -f4 |
  grep -cvxE "ok|fallback|ill-conditioned|rank-deficient|too-few-neighbours")" -eq 0 ]'
centre=$(awk -F, '$1 == 220 { print $2 }' "$work/lu.csv")
check "lv: Lu = 4 at the centre (got $centre)" \
  "awk -v v='$centre' 'BEGIN { d = v - 4; exit !(v != \"\" && d < 1e-8 && d > -1e-8) }'"
expect 0 "apply --stored" -- "$exe" --quiet apply --scheme lv --in "$work/au.csv" --field u \
  --stored --out "$work/lu_stored.csv"
check "--quiet apply prints nothing" '[ ! -s "$work/out" ]'
# The stored apply sums each row in SIMD partial sums: equal to rounding, not bit for bit.
stored=$(awk -F, '$1 == 220 { print $2 }' "$work/lu_stored.csv")
check "stored Lu = matrix-free Lu at the centre ($stored vs $centre)" \
  "awk -v a='$stored' -v b='$centre' 'BEGIN { d = a - b; exit !(a != \"\" && d < 1e-12 && d > -1e-12) }'"
# div((1 + x) grad u) = 4 + 6x: 10 at the centre, to the scheme's O(h^2) for a varying mobility
expect 0 "apply with a mobility column" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --mobility k --h 0.12 --kernel cubic --out "$work/lu_m.csv"
centre_m=$(awk -F, '$1 == 220 { print $2 }' "$work/lu_m.csv")
check "lv with mobility 1 + x: Lu ~ 10 at the centre (got $centre_m)" \
  "awk -v v='$centre_m' 'BEGIN { d = v - 10; exit !(v != \"\" && d < 0.5 && d > -0.5) }'"
expect 0 "apply --gradient G4" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --gradient G4 --out "$work/lu_g4.csv"
# --mean harmonic: 4 m_I m_J / (m_I + m_J) instead of m_I + m_J; for the smooth k = 1 + x it
# differs from the arithmetic result by O(h^2): close to 10 at the centre but not equal
expect 0 "apply --mean harmonic" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --mobility k --h 0.12 --kernel cubic --mean harmonic --out "$work/lu_mh.csv" \
  --timers "$work/th.json"
contains out "mobility mean        harmonic" "apply prints the mobility mean"
contains th.json '"mobility_mean": "harmonic"' "timers carry the mobility mean"
centre_h=$(awk -F, '$1 == 220 { print $2 }' "$work/lu_mh.csv")
check "harmonic lv with mobility 1 + x: Lu ~ 10 at the centre, != arithmetic (got $centre_h)" \
  "awk -v v='$centre_h' -v a='$centre_m' 'BEGIN { d = v - 10; exit !(v != \"\" && d < 0.5 && d > -0.5 && v != a) }'"
expect 0 "apply --mean arithmetic" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --mobility k --h 0.12 --kernel cubic --mean arithmetic --out "$work/lu_ma.csv"
check "--mean arithmetic is the default" \
  '[ "$(awk -F, "\$1 == 220 { print \$2 }" "$work/lu_ma.csv")" = "$centre_m" ]'
expect 1 "bad --mean" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --mean geometric --out "$work/e.csv"
contains err "arithmetic or harmonic" "bad --mean names the choices"
expect 1 "--mean harmonic refused by a scheme without pair mobility" -- "$exe" apply \
  --scheme cspm --in "$work/au.csv" --field u --mean harmonic --out "$work/e.csv"
contains err "cspm" "the refusal names the scheme"
expect 0 "stencil --mean harmonic" -- "$exe" stencil --scheme brookshaw --in "$work/au.csv" \
  --mobility k --mean harmonic --out "$work/Ah.mtx"
expect 2 "mobility column with a zero" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --mobility u --out "$work/lu_m.csv"
contains err "line 2" "zero mobility located at its line"

# stencil: the assembled matrix of the same operator. Without --kernel the list has the
# support of the scheme's default kernel (lv: cubic, 2h), so its pairs are those of
# `neighbours --kernel cubic`.
expect 0 "neighbours cubic" -- "$exe" neighbours "$work/au.csv" --kernel cubic
pairs=$(awk '/^pairs stored/ { print $3 }' "$work/out")
expect 0 "stencil lv" -- "$exe" stencil --scheme lv --in "$work/au.csv" --out "$work/A.mtx"
check "stencil MatrixMarket banner" \
  '[ "$(head -n 1 "$work/A.mtx")" = "%%MatrixMarket matrix coordinate real general" ]'
check "stencil size and nnz = pairs + n ($pairs + 441)" \
  '[ "$(grep -v "^%" "$work/A.mtx" | head -n 1)" = "441 441 $((pairs + 441))" ]'
check "stencil entry count" \
  '[ "$(grep -v "^%" "$work/A.mtx" | tail -n +2 | wc -l)" -eq $((pairs + 441)) ]'
check "stencil row sum of the centre (row 221) is 0" \
  "awk '!/^%/ && ++k > 1 && \$1 == 221 { s += \$3; a += (\$3 < 0 ? -\$3 : \$3) }
        END { exit !(a > 0 && s < 1e-10 * a && s > -1e-10 * a) }' '$work/A.mtx'"
expect 0 "apply --help" -- "$exe" apply --help
contains out "--stored" "apply help lists --stored"
expect 0 "stencil --help" -- "$exe" stencil --help

# errors of apply and stencil
expect 1 "apply unknown scheme" -- "$exe" apply --scheme frob --in "$work/au.csv" --field u \
  --out "$work/e.csv"
contains err "known: " "unknown scheme lists the schemes"
expect 2 "apply missing field" -- "$exe" apply --scheme lv --in "$work/au.csv" --field v \
  --out "$work/e.csv"
contains err "'v'" "missing field named"
contains err "fields: u, k" "missing field lists the fields"
expect 1 "apply bad --gradient" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --gradient G5 --out "$work/e.csv"
expect 1 "apply bad --h" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u --h 0 \
  --out "$work/e.csv"
expect 1 "apply without --out" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u
expect 2 "apply missing input" -- "$exe" apply --scheme lv --in "$work/none.csv" --field u \
  --out "$work/e.csv"
check "failed apply left no file" '[ ! -e "$work/e.csv" ]'
expect 2 "apply into a missing directory" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --out "$work/nodir2/lu.csv"
expect 2 "stencil into a missing directory" -- "$exe" stencil --scheme lv --in "$work/au.csv" \
  --out "$work/nodir2/A.mtx"
check "no partial output in a missing directory" '[ ! -e "$work/nodir2" ]'
expect 1 "stencil unknown scheme" -- "$exe" stencil --scheme frob --in "$work/au.csv" \
  --out "$work/e.mtx"

# --timers: the counts and per-phase timers as JSON, all or nothing
expect 0 "apply --timers" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_t.csv" --timers "$work/t.json"
contains t.json '"scheme": "lv"' "timers name the scheme"
contains t.json '"status": {"ok": ' "timers carry the status counts"
contains t.json '"precompute": ' "timers carry the precompute phase"
contains t.json '"min_pair_distance": 1e-08' "timers carry the pair-distance guard"
contains t.json '"fallback": "Gamma. not SDD' "timers carry the fallback chain"
expect 0 "apply with named thresholds" -- "$exe" apply --scheme lv --in "$work/au.csv" \
  --field u --out "$work/lu_th.csv" --cond-max 1e6 --rank-tol 1e-10 --min-pair-distance 1e-4
contains out "cond_max 1e+06, rank_tol 1e-10, min_pair_distance 0.0001 h" \
  "apply prints the thresholds in force"
expect 1 "bad --min-pair-distance" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_v.csv" --min-pair-distance 0.5
contains err "(0, 0.5)" "bad --min-pair-distance names the range"
expect 1 "bad --cond-max" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_v.csv" --cond-max 0.5
contains t.json '"on_degenerate": "fall_back"' "timers carry the degenerate-row policy"
expect 1 "bad --on-degenerate" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_v.csv" --on-degenerate ignore
contains err "fall_back or refuse" "bad --on-degenerate names the choices"
expect 1 "bad --variant" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_v.csv" --variant x
expect 1 "lv rejects a variant" -- "$exe" apply --scheme lv --in "$work/au.csv" --field u \
  --out "$work/lu_v.csv" --variant 1

# analyse: the spectrum, von Neumann growth factors, audit and maximum principle of a scene's
# operator on its unknowns (docs/stability.md)
expect 0 "analyse --help" -- "$exe" analyse --help
expect 1 "analyse without a scene" -- "$exe" analyse
expect 0 "analyse qsfdi" -- "$exe" analyse "$scenes/qsfdi_test_c.json" cloud.spacing=0.05 \
  cloud.jitter=0.35 --out "$work/sp"
contains out "unknowns             361" "analyse counts the unknowns"
contains out "wrong sign (re >= 0) 0$" "qsfdi has no wrong-sign eigenvalue at K = 0.35"
check "spectrum.csv: header and 361 rows" \
  '[ "$(head -n 1 "$work/sp/spectrum.csv")" = "re,im" ] && [ "$(wc -l < "$work/sp/spectrum.csv")" -eq 362 ]'
check "spectrum.png has the PNG signature" \
  '[ "$(head -c 8 "$work/sp/spectrum.png" | od -An -tx1 | tr -d " \n")" = "89504e470d0a1a0a" ]'
check "analyse left no temporary file" '[ "$(ls -A "$work/sp" | wc -l)" -eq 6 ]'
check "analysis.vtu carries the status, audit bits and growth per particle" \
  'grep -aq "Name=\"status\"" "$work/sp/analysis.vtu" && grep -aq "Name=\"audit_lemma3_mixed\"" "$work/sp/analysis.vtu" && grep -aq "Name=\"vn_max_abs\"" "$work/sp/analysis.vtu"'
contains out "waves N              4 (24 wave vectors)" "analyse: the default wave-vector set"
contains out "s0                   0.05 (cloud.spacing)" "analyse: s0 from the scene"
contains out "^max |growth factor|  1\.0" "analyse: qsfdi growth slightly above 1 at K = 0.35"
contains out "rows pos. off-diag   [1-9]" "analyse: qsfdi has positive off-diagonals at K = 0.35"
contains out "DMP step outside     0$" "analyse: qsfdi keeps the step data in range at K = 0.35"
contains out "DMP linear |u - x|   [0-9.]*e-1[0-9]$" "analyse: qsfdi reproduces g = x"
check "vonneumann.csv: header and 24 x 361 rows" \
  '[ "$(head -n 1 "$work/sp/vonneumann.csv")" = "k,kx,ky,kz,id,re,im,abs" ] && [ "$(wc -l < "$work/sp/vonneumann.csv")" -eq 8665 ]'
check "vonneumann.png has the PNG signature" \
  '[ "$(head -c 8 "$work/sp/vonneumann.png" | od -An -tx1 | tr -d " \n")" = "89504e470d0a1a0a" ]'
contains sp/analysis.json '"min_pair_distance":' "analysis.json carries the thresholds"
contains sp/analysis.json '"fallback":' "analysis.json carries the fallback chain"
check "analysis.json holds the von Neumann, audit and DMP numbers" \
  'grep -q "\"fraction_above_one\":" "$work/sp/analysis.json" && grep -q "\"rows_positive_offdiag\":" "$work/sp/analysis.json" && grep -q "\"maximum_principle\":" "$work/sp/analysis.json" && ! grep -q null "$work/sp/analysis.json"'
# the 5-point Laplacian (lv, unjittered, h = 0.5005 s0): the checkerboard is exactly -1 at
# tau = 0.25 and grows at 0.26 (1 - 8 tau = -1.08) in every row
expect 0 "analyse 5-point tau 0.25" -- "$exe" analyse "$scenes/qsfdi_test_c.json" cloud.spacing=0.05 \
  cloud.jitter=0 cloud.h_ratio=0.5005 operator.scheme=lv --waves 2 --out "$work/sp4"
contains out "^max |growth factor|  1$" "analyse: 5-point max |lambda| = 1 at tau 0.25"
contains out "^growth > 1 pairs     0 of 2888" "analyse: 5-point, 8 wave vectors, no growth at tau 0.25"
expect 0 "analyse 5-point tau 0.26" -- "$exe" analyse "$scenes/qsfdi_test_c.json" cloud.spacing=0.05 \
  cloud.jitter=0 cloud.h_ratio=0.5005 operator.scheme=lv --waves 2 --tau 0.26 --out "$work/sp4"
contains out "^max |growth factor|  1.08$" "analyse: 5-point max |lambda| = 1.08 at tau 0.26"
contains out "^growth > 1 particles 361$" "analyse: every row grows at tau 0.26"
expect 1 "analyse --tau 0" -- "$exe" analyse "$scenes/qsfdi_test_c.json" --tau 0
contains err "\-\-tau '0': needs a number > 0" "bad --tau named"
expect 1 "analyse --tau nan" -- "$exe" analyse "$scenes/qsfdi_test_c.json" --tau nan
contains err "\-\-tau" "non-finite --tau named"
expect 1 "analyse --tau without a value" -- "$exe" analyse "$scenes/qsfdi_test_c.json" --tau
contains err "\-\-tau needs" "missing --tau value named"
expect 1 "analyse --waves 0" -- "$exe" analyse "$scenes/qsfdi_test_c.json" --waves 0
contains err "\-\-waves '0': needs a whole number in 1..64" "bad --waves named"
expect 1 "analyse --waves 2.5" -- "$exe" analyse "$scenes/qsfdi_test_c.json" --waves 2.5
contains err "\-\-waves '2.5'" "fractional --waves named"
expect 0 "analyse icspm" -- "$exe" analyse "$scenes/qsfdi_test_c.json" operator.scheme=icspm \
  cloud.h_ratio=1.2 cloud.jitter=0.35 cloud.spacing=0.05 --out "$work/sp2"
check "icspm has wrong-sign eigenvalues at K = 0.35, h = 1.2 s0" \
  '[ "$(awk "/^wrong sign/ { print \$NF }" "$work/out")" -gt 0 ]'
# a mixed problem: the solve task's Neumann groups are applied, and its flux rows enter with
# the inward sign: no wrong-sign eigenvalue, no non-positive diagonal, g = x reproduced with
# its flux on the Neumann rows
expect 0 "analyse a mixed Dirichlet / Neumann scene" -- "$exe" --quiet analyse \
  "$scenes/lv_mixed.json" cloud.spacing=0.05 --out "$work/sp4"
contains out "unknowns             460" "the Neumann face particles are unknowns"
contains out "wrong sign (re >= 0) 0" "the mixed operator is positive stable"
contains out "K diagonal <= 0      0 of 460" "Neumann rows counted with the inward sign"
contains out "DMP linear outside   0" "g = x with its flux stays in the boundary range"
check "g = x is reproduced with Neumann rows" \
  'awk "/^DMP linear \|u - x\|/ { n++; ok = \$NF < 1e-10 } END { exit !(n == 1 && ok) }" "$work/out"'
expect 2 "analyse refuses more than 5000 unknowns" -- "$exe" analyse "$scenes/qsfdi_test_c.json" \
  --out "$work/sp3"
contains err "more than 5000" "analyse names the limit"
check "refused analyse wrote nothing" '[ ! -e "$work/sp3" ]'

# hostile sweep files and clouds (issue 16): caps refuse at once, with the count and the cap
sed 's/"cloud.seed": { "from": 1, "count": 2 }/"cloud.seed": { "from": 1, "count": 1000000 },\
  "cloud.jitter": { "from": 0, "count": 1000000, "step": 1e-7 }/' "$work/sw.json" > "$work/swbig.json"
expect 2 "sweep --plan of 4e12 combinations refuses at once" -- timeout 20 "$exe" sweep \
  "$work/swbig.json" --plan
contains err "key 'grid': 4000000000000 combinations, more than the 100000 a sweep may have" \
  "sweep names the combination count and the cap"

# issue 16: the writer. A link is followed (the link stays), devices are written into and
# their write errors reported, a directory is refused, SIGTERM removes the temporary file.
expect 0 "cloud into a symbolic link" -- sh -c "cd '$work' && ln -s lt.csv l.csv && '$(readlink -f "$exe")' cloud -o l.csv"
check "the link stays a link to its updated target" '[ -L "$work/l.csv" ] && [ "$(wc -l < "$work/lt.csv")" -eq 122 ]'
expect 0 "cloud into /dev/null" -- "$exe" cloud -o /dev/null
check "/dev/null is still a device" '[ -c /dev/null ]'
if [ -c /dev/full ]; then
  expect 2 "cloud into /dev/full" -- "$exe" cloud -o /dev/full
  contains err "/dev/full: write error: No space left on device" "/dev/full names the reason"
fi
mkdir "$work/outdir"
expect 2 "cloud onto a directory" -- "$exe" cloud -o "$work/outdir"
contains err "outdir: is a directory" "a directory in the way is named"
mkdir "$work/sig"
"$exe" cloud --dim 3 --s0 0.01 -o "$work/sig/big.csv" > /dev/null 2>&1 &
pid=$!
for _ in $(seq 200); do
  ls "$work/sig" | grep -q '\.tmp\.' && break
  sleep 0.05
done
kill -TERM "$pid" 2> /dev/null
wait "$pid"
sig_rc=$?
check "SIGTERM kills the writer with the signal (exit $sig_rc)" '[ "$sig_rc" -eq 143 ]'
check "SIGTERM leaves no temporary file" '[ -z "$(ls -A "$work/sig")" ]'

# issue 16: exit 2 (bad input) for a task the scheme cannot take and for an expression that
# does not compile, in --plan as in the run
expect 2 "run: a scheme without the task's gradient" -- "$exe" run cloud.spacing=0.1 operator.scheme=brookshaw
contains err "scheme 'brookshaw' has no gradient" "the refusal names the scheme"
expect 2 "run --plan: a scheme without the task's gradient" -- "$exe" run operator.scheme=brookshaw --plan
expect 2 "run --plan: an expression that does not compile" -- "$exe" run "fields.u=sin(" --plan
contains err "fields.u: column 5:" "--plan gives the run's message"
sed 's/"sin(6\*x + 8\*y)"/"sin(6*x +"/' "$work/sw.json" > "$work/swexpr.json"
expect 2 "sweep --plan: an expression that does not compile" -- "$exe" sweep "$work/swexpr.json" --plan
contains err "fields.u: column" "sweep --plan names the expression"

# Hostile clouds and paths (issue 16 items 4, 7, 9): refused with exit 2 and a reason, never a hang.
printf 'x,y,V,h,kind,nx,ny,u\n-1e308,0,1,1,interior,0,0,0\n1e308,0,1,1,interior,0,0,0\n' > "$work/wide.csv"
expect 2 "neighbours: a cloud spanning +-1e308" -- timeout 20 "$exe" neighbours "$work/wide.csv"
contains err "extent overflows" "neighbours names the overflowing extent"
expect 2 "apply: a cloud spanning +-1e308" -- timeout 20 "$exe" apply --scheme lv --field u \
  --in "$work/wide.csv" --out "$work/wide_lu.csv"
contains err "extent overflows" "apply names the overflowing extent"
expect 2 "stencil: a cloud spanning +-1e308" -- timeout 20 "$exe" stencil --scheme lv \
  --in "$work/wide.csv" --out "$work/wide.mtx"
contains err "extent overflows" "stencil names the overflowing extent"
cat > "$work/wide_scene.json" <<'EOF'
{ "dim": 2, "cloud": { "source": "file", "file": "wide.csv" },
  "fields": { "w": "x" }, "tasks": [ { "type": "laplacian", "field": "w" } ] }
EOF
expect 2 "run: a cloud spanning +-1e308" -- timeout 20 "$exe" run "$work/wide_scene.json"
contains err "extent overflows" "run names the overflowing extent"
printf 'x,y,V,h,kind,nx,ny,u\n0,0,1,1,interior,0,0,0\n0.5,0,1,1,interior,0,0,0\n' > "$work/two_u.csv"
expect 2 "apply: h = 1e300" -- timeout 20 "$exe" apply --scheme lv --in "$work/two_u.csv" \
  --field u --h 1e300 --out "$work/h_lu.csv"
contains err "smoothing length" "apply names the absurd h"
printf 'x,y,V,h,kind,nx,ny\n' > "$work/empty.csv"
expect 2 "neighbours: a cloud without particles" -- "$exe" neighbours "$work/empty.csv"
contains err "the cloud has no particles" "neighbours says the cloud is empty"
sed 's/wide.csv/empty.csv/' "$work/wide_scene.json" > "$work/empty_scene.json"
expect 2 "run: a cloud without particles" -- "$exe" run "$work/empty_scene.json"
contains err "the cloud has no particles" "run says the cloud is empty"
printf 'x,y,V,h,kind,nx,ny\n0,0,1,1,interior,0,0\n1,0,1,1,neumann,0,0\n' > "$work/nonormal.csv"
expect 2 "neighbours: a Neumann particle with a zero normal" -- "$exe" neighbours \
  "$work/nonormal.csv"
contains err "particle 1: Neumann particle with a zero normal" "the zero normal's particle named"
mkdir -p "$work/adir.json"
expect 2 "run: a directory as the scene" -- "$exe" run "$work/adir.json"
contains err "Is a directory" "the directory's reason given"
sed 's/wide.csv/c.vtp/' "$work/wide_scene.json" > "$work/vtp_scene.json"
sed 's/UnstructuredGrid/PolyData/g' "$work/c.vtu" > "$work/c.vtp"
expect 0 "run: a .vtp cloud.file goes to the VTK reader" -- "$exe" run "$work/vtp_scene.json"
contains out "441 particles" "the .vtp cloud read as VTK PolyData, not as CSV"
sed 's/wide.csv/c.txt/' "$work/wide_scene.json" > "$work/txt_scene.json"
cp "$work/two_u.csv" "$work/c.txt"
expect 2 "run: an unknown cloud.file extension" -- "$exe" run "$work/txt_scene.json"
contains err "unknown extension (a cloud file is .csv, .vtu or .vtp)" "the extension refusal says what is read"
expect 0 "neighbours: a .vtp cloud goes to the VTK reader" -- "$exe" neighbours "$work/c.vtp"
contains out "particles            441 (2D)" "neighbours reads the .vtp as VTK PolyData, not as CSV"
expect 0 "apply: a .vtu cloud goes to the VTK reader" -- "$exe" apply --scheme qsfdi \
  --in "$work/c.vtu" --field p --out "$work/vtu_apply.csv"
contains out "441 rows" "apply reads the .vtu as VTK"
expect 2 "apply: an unknown cloud extension" -- "$exe" apply --scheme qsfdi --in "$work/c.txt" \
  --field p --out "$work/txt_apply.csv"
contains err "c.txt: unknown extension" "apply names the file and the rule"
# A file cloud's plan reads the file (its size, its h / s0), and cloud.h_ratio on a file cloud
# scales each particle's own spacing V^(1/D) unless cloud.spacing is given.
"$exe" --quiet cloud --s0 0.05 --h-ratio 2.6 -o "$work/f26.csv"
cat > "$work/f26.json" <<EOF
{ "dim": 2, "cloud": { "source": "file", "file": "f26.csv" }, "fields": { "u": "x*x" },
  "tasks": [ { "name": "lap", "type": "laplacian", "field": "u", "exact": "2",
               "region": "interior" } ] }
EOF
expect 0 "run --plan on a file cloud" -- "$exe" run "$work/f26.json" --plan
contains out "441 particles from" "the plan counts the file's particles"
contains out "h = 2.6 s0 (mean h / V^(1/2))" "the plan measures the file's h / s0"
contains out "about 190 per particle" "the neighbour estimate from the file's h"
expect 0 "plan: cloud.h_ratio on a file cloud" -- "$exe" run "$work/f26.json" --plan \
  cloud.h_ratio=1.3
contains out "h = 1.3 s0" "h_ratio scales the file's own spacing, not the default cloud.spacing"
expect 0 "plan: cloud.h_ratio and cloud.spacing on a file cloud" -- "$exe" run \
  "$work/f26.json" --plan cloud.h_ratio=1.3 cloud.spacing=0.1
contains out "h = 2.6 s0" "with cloud.spacing given, h = h_ratio * spacing"
# A Laplacian task's box region measures interior particles only: the Dirichlet layer's rows
# are the identity, not L u (its error was counted as -2 per boundary particle).
"$exe" --quiet cloud --s0 0.05 --h-ratio 1.3 --boundary-layer -o "$work/fb.csv"
cat > "$work/fb.json" <<EOF
{ "dim": 2, "cloud": { "source": "file", "file": "fb.csv" }, "fields": { "u": "x*x" },
  "tasks": [ { "name": "box", "type": "laplacian", "field": "u", "exact": "2",
               "region": { "lo": [0, 0], "hi": [1, 1] } } ] }
EOF
expect 0 "run: a Laplacian over a box that holds the Dirichlet layer" -- "$exe" run \
  "$work/fb.json" "outputs.report=$work/fb_report.json"
contains out "over 361 particles" "the box counts the 19 x 19 interior particles, not 441"
check "the Laplacian over the box is exact for x^2, the boundary rows left out" \
  "python3 -c 'import json,sys; t=json.load(open(sys.argv[1]))[\"tasks\"][0]; assert t[\"region_particles\"]==361 and t[\"norms\"][\"rel_l2\"]<1e-12' '$work/fb_report.json'"
# apply agrees with run on the boundary rows: Lu is 0 there as the laplacian task writes it,
# Au the operator's product (the identity on a Dirichlet row: u itself).
awk -F, 'NR == 1 { print $0 ",u"; next } { printf "%s,%.17g\n", $0, $1 * $1 }' "$work/fb.csv" \
  > "$work/fbu.csv"
expect 0 "apply on a cloud with a Dirichlet layer" -- "$exe" --quiet apply --scheme qsfdi \
  --in "$work/fbu.csv" --field u --out "$work/fblu.csv"
check "apply: Lu = 0 and Au = u on the Dirichlet rows, Lu = Au = 2 inside" \
  "python3 -c 'import csv,sys
c=list(csv.DictReader(open(sys.argv[1]))); l=list(csv.DictReader(open(sys.argv[2])))
assert len(c)==len(l)==441
for p,r in zip(c,l):
    if p[\"kind\"]==\"interior\": assert abs(float(r[\"Lu\"])-2)<1e-9 and r[\"Lu\"]==r[\"Au\"]
    else: assert float(r[\"Lu\"])==0 and abs(float(r[\"Au\"])-float(p[\"u\"]))<1e-15' '$work/fbu.csv' '$work/fblu.csv'"
expect 1 "cloud --jitter 5" -- "$exe" cloud --jitter 5 -o "$work/j.csv"
contains err "option --jitter: a number in \[0, 1) expected" "the jitter limit of the scenes"
check "cloud --jitter 5 wrote nothing" '[ ! -e "$work/j.csv" ]'

# The memory estimate under an address-space limit (issue 16 item 8): refused up front, the
# limit named, by run and by cloud alike; sysinfo says which limit applies.
expect 0 "run --plan of 10^6 particles fits without a limit" -- "$exe" run cloud.spacing=0.01 --plan
expect 4 "run under ulimit -v 800000 is refused by the estimate" -- \
  bash -c 'ulimit -v 800000 && exec "$0" run cloud.spacing=0.01 --plan' "$exe"
contains err "the limit that applies: RLIMIT_AS" "the refusal names RLIMIT_AS"
expect 4 "cloud under ulimit -v 800000 is refused by the estimate" -- \
  bash -c 'ulimit -v 800000 && exec "$0" cloud --s0 0.0002 -o "$1"' "$exe" "$work/big.csv"
contains err "pstencil: cloud: the cloud needs about 1.23 GB" "cloud gives its estimate"
contains err "the limit that applies: RLIMIT_AS" "cloud names RLIMIT_AS"
check "the refused cloud wrote nothing" '[ ! -e "$work/big.csv" ]'
expect 0 "sysinfo under ulimit -v 800000" -- bash -c 'ulimit -v 800000 && exec "$0" sysinfo' "$exe"
contains out "memory available .*(limit: RLIMIT_AS" "sysinfo names the limit that applies"

# ParaView outputs (docs/io.md): a gradient with exact values gives g_exact and g_error fields,
# the VTU joins each into one 3-component array, .vtp is PolyData, other extensions are refused.
cat > "$work/grad.json" <<'EOF2'
{"cloud": {"spacing": 0.1}, "fields": {"u": "x*x + y"},
 "tasks": [{"type": "gradient", "name": "g", "field": "u", "exact": ["2*x", "1"]}],
 "outputs": {"csv": "g.csv", "vtu": "g.vtp", "fields": ["g"], "vtu_compress": true}}
EOF2
expect 0 "run a gradient with exact values" -- \
  bash -c 'cd "$1" && exec "$2" --quiet run grad.json' _ "$work" "$exe"
check "outputs.fields g selects g, g_exact and g_error" \
  '[ "$(head -n 1 "$work/g.csv")" = \
     "x,y,V,h,kind,nx,ny,g_x,g_y,g_exact_x,g_exact_y,g_error_x,g_error_y" ]'
check "the .vtp is compressed PolyData with g_error as one vector and a status" \
  'grep -aq "<VTKFile type=\"PolyData\".*vtkZLibDataCompressor" "$work/g.vtp" &&
   grep -aq "Name=\"g_error\" NumberOfComponents=\"3\"" "$work/g.vtp" &&
   grep -aq "Name=\"status\"" "$work/g.vtp"'
expect 2 "outputs.vtu with another extension is refused" -- \
  "$exe" --quiet run "$work/grad.json" 'outputs={"vtu":"g.vtk"}'
contains err "expected a .vtu (UnstructuredGrid) or .vtp (PolyData) file name" \
  "the refusal says why"

# A solve with boundary groups has no base operator: its VTU carries its own operator's status.
cat > "$work/sv.json" <<'EOF2'
{"cloud": {"spacing": 0.1}, "operator": {"scheme": "lv"},
 "tasks": [{"type": "solve", "name": "u", "rhs": "2", "exact": "x*x",
            "boundary": [{"where": "all", "type": "dirichlet", "value": "x*x"}]}],
 "outputs": {"vtu": "sv.vtu"}}
EOF2
expect 0 "run a grouped solve" -- bash -c 'cd "$1" && exec "$2" --quiet run sv.json' _ "$work" "$exe"
check "the grouped solve's VTU has status, u_exact and u_error" \
  'grep -aq "Name=\"status\"" "$work/sv.vtu" && grep -aq "Name=\"u_error\"" "$work/sv.vtu"'

# Periodic boxes on the command line (--periodic, --box). A 17 x 17 lattice of s0 = 1/16 on
# [0, 1]^2 tiles the torus of period 17/16 = 1.0625 exactly, in the box [-s0/2, 1 + s0/2).
box=-0.03125,-0.03125,1.03125,1.03125
expect 0 "cloud for the periodic box" -- "$exe" cloud --dim 2 --lo 0,0 --hi 1,1 --s0 0.0625 \
  --h-ratio 1 -o "$work/per.csv"
# cubic support 2h = 2 s0: every particle of the torus has the 8 lattice points closer than 2 s0
expect 0 "neighbours --periodic xy" -- "$exe" neighbours "$work/per.csv" --kernel cubic \
  --periodic xy --box "$box"
contains out "neighbours           min 8, mean 8.00, max 8, isolated 0" "no particle has a face"
expect 0 "stencil --periodic xy" -- "$exe" stencil --scheme brookshaw --kernel cubic \
  --in "$work/per.csv" --out "$work/per.mtx" --periodic xy --box "$box"
contains out "wrote 289 x 289 matrix, 2601 entries" "every row has 8 neighbours + its diagonal"
# The same lattice jittered, with u = sin(kx) cos(ky), k = 2 pi / 1.0625: L u = -2 k^2 u on
# every row, the rows at the faces included.
expect 0 "jittered cloud for the periodic box" -- "$exe" cloud --dim 2 --lo 0,0 --hi 1,1 \
  --s0 0.0625 --jitter 0.3 --seed 5 --h-ratio 1.2 -o "$work/perj.csv"
k_awk='k = 2 * 3.14159265358979324 / 1.0625'
awk -F, "NR == 1 { print \$0 \",u\"; next } { $k_awk; printf \"%s,%.17g\\n\", \$0, sin(k * \$1) * cos(k * \$2) }" \
  "$work/perj.csv" > "$work/peru.csv"
# translated by 0.3 along x and folded back into the box, u unchanged: the same torus
awk -F, -v OFS=, 'NR == 1 { print; next } { x = $1 + 0.3; if (x >= 1.03125) x -= 1.0625;
  $1 = sprintf("%.17g", x); print }' "$work/peru.csv" > "$work/pert.csv"
expect 0 "apply --periodic xy" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" --field u \
  --out "$work/per_lu.csv" --periodic xy --box "$box"
contains out "periodic             xy" "apply prints the periodic axes"
expect 0 "apply --periodic xy, translated cloud" -- "$exe" --quiet apply --scheme qsfdi \
  --in "$work/pert.csv" --field u --out "$work/per_lt.csv" --periodic=xy --box="$box"
expect 0 "apply without --periodic" -- "$exe" --quiet apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/per_l0.csv"
# max |Au - exact| / max |exact| over every row
rel_err() {
  paste -d, "$work/peru.csv" "$1" | awk -F, "NR > 1 { $k_awk; e = -2 * k * k * \$8; d = \$10 - e;
    if (d < 0) d = -d; if (e < 0) e = -e; if (d > m) m = d; if (e > big) big = e }
    END { printf \"%.6g\\n\", m / big }"
}
per_err=$(rel_err "$work/per_lu.csv")
open_err=$(rel_err "$work/per_l0.csv")
check "periodic apply: L u = -2 k^2 u on every row ($per_err < 0.1)" \
  "awk 'BEGIN { exit !($per_err < 0.1) }'"
check "without --periodic the face rows are off ($open_err > 0.2)" \
  "awk 'BEGIN { exit !($open_err > 0.2) }'"
check "apply is invariant under a translation through the faces (same ids, to rounding)" \
  "paste -d, '$work/per_lu.csv' '$work/per_lt.csv' | awk -F, 'NR > 1 { d = \$3 - \$7;
    if (d < 0) d = -d; a = \$3; if (a < 0) a = -a; if (d > m) m = d; if (a > big) big = a;
    if (\$3 != \$3 + 0 || \$1 != \$5) bad = 1 } END { exit bad || !(m < 1e-10 * big) }'"
check "periodic apply: every value finite" \
  "! awk -F, 'NR > 1' '$work/per_lu.csv' | grep -qi 'nan\|inf'"
# refusals: exit 1 for the options themselves, 2 for what does not fit the cloud
expect 1 "--periodic: unknown axis" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xw --box "$box"
contains err "option --periodic: unknown axis 'w' (the axes are x, y and z) (got 'xw')" \
  "the bad axis is named"
expect 1 "--periodic: repeated axis" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xyx --box "$box"
contains err "axis 'x' is given twice" "the repeated axis is named"
expect 1 "--periodic: empty" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic= --box "$box"
expect 2 "--periodic z on a 2D cloud" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xz --box "$box"
contains err "is 2D, it has no z axis" "the missing axis is named"
expect 1 "--box: three numbers" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy --box 0,0,1
contains err "option --box: 4 (2D: x0,y0,x1,y1) or 6 (3D: x0,y0,z0,x1,y1,z1) comma-separated" \
  "the box's form is given"
expect 1 "--box: not a number" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy --box 0,0,1,one
expect 1 "--box: an empty number" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy --box 0,,1,1
expect 2 "--box: 3D box on a 2D cloud" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy --box 0,0,0,1,1,1
contains err "is 2D: 4 numbers expected (x0,y0,x1,y1), got 6" "the count is explained"
expect 1 "--box: hi not above lo" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic x --box 0,0,0,1
contains err "hi must exceed lo along x" "the empty box is refused"
expect 1 "--periodic without --box" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy
contains err "apply: --periodic needs --box" "the missing box is named"
expect 1 "--box without --periodic" -- "$exe" stencil --scheme qsfdi --in "$work/peru.csv" \
  --out "$work/x.mtx" --box "$box"
contains err "stencil: --box needs --periodic" "the missing axes are named"
expect 2 "a particle outside the box" -- "$exe" apply --scheme qsfdi --in "$work/peru.csv" \
  --field u --out "$work/x.csv" --periodic xy --box 0,0,1,1
contains err "lies outside the periodic box" "the particle outside is named"
expect 2 "a period within twice the neighbour radius" -- "$exe" apply --scheme qsfdi \
  --in "$work/peru.csv" --field u --out "$work/x.csv" --periodic x --box "$box" --h 0.2
contains err "must exceed twice the neighbour radius" "the short period is explained"
check "no refused command wrote its output" '[ ! -e "$work/x.csv" ] && [ ! -e "$work/x.mtx" ]'
# A scene on the same file cloud: cloud.box gives the periodic box the file does not record.
cat > "$work/per_scene.json" <<EOF2
{ "cloud": { "source": "file", "file": "peru.csv", "periodic": true,
             "box": { "lo": [-0.03125, -0.03125], "hi": [1.03125, 1.03125] } },
  "tasks": [ { "type": "solve", "name": "p", "precond": "jacobi",
               "rhs": "-2*(2*pi/1.0625)^2*sin(2*pi*x/1.0625)*cos(2*pi*y/1.0625)",
               "exact": "5 + sin(2*pi*x/1.0625)*cos(2*pi*y/1.0625)" } ],
  "outputs": { "report": "$work/per_scene.report.json" } }
EOF2
expect 0 "run a scene on a periodic file cloud" -- "$exe" run "$work/per_scene.json"
contains out "exact shifted by -[0-9.]* to u's mean" "the shift of the exact solution is said"
check "periodic file scene: exact moved by about -5, rel_l2 against it < 0.1" \
  "python3 -c 'import json,sys; t=json.load(open(sys.argv[1]))[\"tasks\"][0]; assert t[\"solver\"][\"fix_mean\"] and abs(t[\"exact_shift\"]+5)<1e-2 and t[\"norms\"][\"rel_l2\"]<0.1, t' '$work/per_scene.report.json'"
expect 2 "a file cloud outside its cloud.box" -- "$exe" run "$work/per_scene.json" \
  'cloud.box.lo=[0,0]' 'cloud.box.hi=[1,1]'
contains err "cloud.box: particle [0-9]*: [xy] = .* lies outside the periodic box" \
  "a particle outside cloud.box is refused"
expect 2 "cloud.box on a lattice" -- "$exe" run 'cloud.box={"lo":[0,0,0],"hi":[1,1,1]}'
contains err "key 'cloud.box': applies only when 'cloud.source' is file" "cloud.box refused"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
