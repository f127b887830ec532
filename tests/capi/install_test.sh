#!/usr/bin/env bash
# Installs the C API into a temporary prefix, then builds and runs examples/c against it twice: with
# CMake's find_package(jointcomp) and with pkg-config.
# usage: install_test.sh <build dir> <source dir> <work dir> <C compiler>
set -euo pipefail
build="$1"
source="$2"
work="$3"
cc="$4"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"

echo "== find_package(jointcomp)"
cmake -S "$source/examples/c" -B "$work/find_package" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_BUILD_TYPE=Release >"$work/configure.log"
cmake --build "$work/find_package" >"$work/build.log"
"$work/find_package/spiral"

echo "== pkg-config jointcomp"
pc_file=$(find "$prefix" -name jointcomp.pc)
export PKG_CONFIG_PATH="$(dirname "$pc_file")"
libdir=$(pkg-config --variable=libdir jointcomp)
datadir=$(pkg-config --variable=datadir jointcomp)
# shellcheck disable=SC2046 # the flags are words
"$cc" -std=c99 -Wall -Wextra -Wpedantic -Werror "$source/examples/c/spiral.c" -o "$work/spiral_pkg_config" \
  $(pkg-config --cflags --libs jointcomp) -Wl,-rpath,"$libdir"
"$work/spiral_pkg_config" "$datadir/robots/rx170.urdf" "$datadir/params/rx170.json"

echo "== the installed Python package finds the installed library"
found=$(env -u JOINTCOMP_LIBRARY PYTHONPATH="$prefix/lib/python3/dist-packages" PYTHONDONTWRITEBYTECODE=1 \
  /usr/bin/python3 -c 'import jointcomp; print(jointcomp.library_path)')
echo "$found"
case "$found" in
  "$prefix"/lib/*) ;;
  *) echo "expected the library under $prefix/lib"; exit 1 ;;
esac

echo "== the installed tool runs from the prefix, with no source tree"
(cd "$work" && "$prefix/bin/jointcomp" --version) | tee "$work/version.txt"
grep -qF "files: $(realpath "$prefix")/share/jointcomp (installed)" "$work/version.txt"
(cd "$work" && "$prefix/bin/jointcomp" kinematics) >"$work/kinematics.txt"
grep -q "rx170" "$work/kinematics.txt" || { cat "$work/kinematics.txt"; exit 1; }
