#!/usr/bin/env bash
# The library as a user gets it: `cmake --install` into a fresh prefix, then
#  1. examples/ built against it with find_package(Ferry) (its own
#     CMakeLists.txt), and `mpirun -np 4 in_situ`: two ranks render on a
#     communicator split off MPI_COMM_WORLD and write a PNG;
#  2. a program built with `pkg-config --cflags --libs ferry` renders;
#  3. the installed command and Python module run.
set -euo pipefail
ferry=$(realpath "$1")
source_dir=$(realpath "$2")
source "$source_dir/tests/tools/mpi_env.sh"
build=$(dirname "$ferry")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
libdir=$(dirname "$(find "$prefix" -name 'libferry.so' | head -1)")
[ -f "$prefix/include/ferry/ferry.h" ] && [ -f "$libdir/cmake/Ferry/FerryConfig.cmake" ] &&
  [ -f "$libdir/pkgconfig/ferry.pc" ] && [ -x "$prefix/bin/ferry" ] ||
  { echo "FAIL: the install lacks a header, the library, its package or the command" >&2; exit 1; }
echo "  installed into a fresh prefix: $(wc -l < "$work/install.log") files"

echo "== examples/ against the installed package"
cmake -S "$source_dir/examples" -B "$work/examples" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" > "$work/configure.log"
cmake --build "$work/examples" > "$work/build.log"
timeout 120 mpirun --oversubscribe -np 4 "$work/examples/in_situ" "$work/in_situ.png"
python3 - "$work/in_situ.png" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", data[16:24])
assert (width, height) == (320, 240), (width, height)
print(f"  in_situ: a {width}x{height} PNG")
PY

echo "== pkg-config"
cat > "$work/hello.cpp" <<'CPP'
#include <ferry/ferry.h>
#include <cstdio>
int main() {
  ferry::api::Options o;
  o.width = 16;
  o.height = 12;
  const ferry::api::Image image = ferry::api::render("builtin:cornell", o);
  std::printf("  pkg-config build: a %dx%d image\n", image.width, image.height);
  return image.rgba.size() == 16 * 12 * 4 ? 0 : 1;
}
CPP
export PKG_CONFIG_PATH="$libdir/pkgconfig"
# shellcheck disable=SC2046
g++ "$work/hello.cpp" -o "$work/hello" $(pkg-config --cflags --libs ferry) -Wl,-rpath,"$libdir"
"$work/hello"

echo "== the installed command and module"
"$prefix/bin/ferry" render builtin:cornell --size 16x12 -q -o "$work/c.png"
module=$(dirname "$(find "$prefix" -name 'ferry*.so' -path '*python*' | head -1)")
PYTHONPATH="$module" /usr/bin/python3 -c "
import ferry
assert ferry.render('builtin:cornell', size=(16, 12)).shape == (12, 16, 3)
print('  installed module: ferry.render works')"
echo "library_test: all passed"
