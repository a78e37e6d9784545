#!/usr/bin/env bash
# Install the built pstencil into a temporary prefix, then build and run a downstream program
# against it with find_package (shared and static targets) and with pkg-config.
# Usage: run.sh BUILD_DIR DOWNSTREAM_SOURCE_DIR
set -euo pipefail
build=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"

cmake -S "$src" -B "$work/b" -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure.log"
cmake --build "$work/b" > "$work/build.log"
"$work/b/use_shared"
"$work/b/use_static"
if ldd "$work/b/use_static" | grep -q libpstencil; then
  echo "downstream: use_static is linked to the shared library" >&2
  exit 1
fi

pc=$(dirname "$(find "$work/prefix" -name pstencil.pc | head -n 1)")
libdir=$(PKG_CONFIG_PATH="$pc" pkg-config --variable=libdir pstencil)
cc -std=c17 "$src/main.c" $(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs pstencil) -o "$work/use_pc"
LD_LIBRARY_PATH="$libdir" "$work/use_pc"
echo "downstream: find_package (shared, static) and pkg-config builds ran"
