#!/usr/bin/env bash
# Install pstencil's build dependencies from Debian packages, only when something is missing.
# Idempotent: a second run changes nothing. Needs root (or sudo) only when it installs.
set -euo pipefail

packages=(build-essential cmake pkg-config libopenblas-dev liblapacke-dev libhwloc-dev
          libbenchmark-dev libhypre-dev libopenmpi-dev python3 python3-vtk9
          libcjson-dev gnuplot-nox libexpat1-dev zlib1g-dev
          petsc-dev openmpi-bin # optional: the PETSc solves and MPI ranks (test_ranks)
          clang libclang-rt-dev libomp-dev) # the last three: the fuzzers (scripts/fuzz.sh)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all dependencies present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update
$sudo apt-get install -y --no-install-recommends "${missing[@]}"
