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
expect 0 "run (small)" -- "$exe" run --s0 0.05
contains out "particles            9261 (3D)" "run particle count (21^3)"
contains out "time neighbours" "run prints timings"
expect 0 "run --help" -- "$exe" run --help

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
