#!/usr/bin/env bash
# Install the built pstencil into a temporary prefix, then build and run a downstream program
# against it with find_package (shared and static targets; a C and a C++-only project, the latter
# the example of docs/embedding.md) and with pkg-config (C, and C++ with g++).
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

# docs/embedding.md quotes the C++ consumer in full: its one cpp block must be the file.
python3 - "$src/../../docs/embedding.md" "$src/cxx/main.cpp" <<'PY'
import re, sys
page, code = (open(p).read() for p in sys.argv[1:])
blocks = re.findall(r"```cpp\n(.*?)```", page, re.S)
if blocks != [code]:
    sys.exit("downstream: the example in docs/embedding.md differs from "
             "tests/downstream/cxx/main.cpp")
PY

# The C++-only project (no C language enabled), shared and static, run without LD_LIBRARY_PATH.
cmake -S "$src/cxx" -B "$work/bxx" -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure-cxx.log"
cmake --build "$work/bxx" > "$work/build-cxx.log"
env -u LD_LIBRARY_PATH "$work/bxx/use_shared_cxx"
env -u LD_LIBRARY_PATH "$work/bxx/use_static_cxx"

# Installed binaries find their libraries by an $ORIGIN-relative run path.
so=$(find "$work/prefix" -name 'libpstencil.so.*.*' | head -n 1)
for f in "$work/prefix/bin/pstencil" "$so"; do
  if ! readelf -d "$f" | grep -E 'R(UN)?PATH' | grep -q '\$ORIGIN'; then
    echo "downstream: $f has no \$ORIGIN run path" >&2
    exit 1
  fi
done
env -u LD_LIBRARY_PATH "$work/prefix/bin/pstencil" --version

pc=$(dirname "$(find "$work/prefix" -name pstencil.pc | head -n 1)")
libdir=$(PKG_CONFIG_PATH="$pc" pkg-config --variable=libdir pstencil)
cc -std=c17 "$src/main.c" $(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs pstencil) -o "$work/use_pc"
LD_LIBRARY_PATH="$libdir" "$work/use_pc"
g++ -std=c++17 -Wall -Wextra -Wpedantic -Werror "$src/cxx/main.cpp" \
  $(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs pstencil) -o "$work/use_pc_cxx"
LD_LIBRARY_PATH="$libdir" "$work/use_pc_cxx"
echo "downstream: C and C++ find_package (shared, static) and pkg-config builds ran"
