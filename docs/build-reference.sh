#!/usr/bin/env bash
# Builds the reference documentation into BUILD_DIR/reference: the C API's from its header's comments with
# Doxygen (c/html/index.html) and the Python package's from its docstrings with pydoc (python/jointcomp.html,
# one page per module). Fails on any Doxygen warning, on a public C function, type or macro without its
# comment, and on a public Python name without its docstring, naming each (the CTest docs_reference runs it).
# usage: bash docs/build-reference.sh [BUILD_DIR]   (default build/release; the Python modules are imported,
# so the C library is built there first: an unconfigured folder is configured with the release preset;
# JOINTCOMP_LIBRARY set: that library is used and nothing is built)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build/release}"
command -v doxygen >/dev/null || { echo "build-reference: doxygen is missing (bash packaging/install-deps.sh)" >&2; exit 2; }
if [ -z "${JOINTCOMP_LIBRARY:-}" ]; then
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build" --preset release >/dev/null
  fi
  cmake --build "$build" --target jointcomp_capi -j"$(nproc)" >/dev/null
fi
mkdir -p "$build"
build="$(cd "$build" && pwd)"
out="$build/reference"
rm -rf "$out"
mkdir -p "$out"

# The C API. Doxygen reads the Doxyfile's $(...) from the environment.
JOINTCOMP_SOURCE_DIR="$root" JOINTCOMP_REFERENCE_DIR="$out" doxygen "$root/docs/reference/Doxyfile" || true
if [ -s "$out/c-warnings.log" ] || [ ! -f "$out/c/html/index.html" ]; then
  echo "build-reference: Doxygen's warnings on the C API (docs/reference/Doxyfile):" >&2
  cat "$out/c-warnings.log" >&2
  exit 1
fi

# The Python package, against the library just built; Debian's interpreter (the python3 first on PATH may be
# another one, without numpy).
library="${JOINTCOMP_LIBRARY:-$build/capi/libjointcomp.so}"
[ -f "$library" ] || { echo "build-reference: no library $library" >&2; exit 1; }
JOINTCOMP_LIBRARY="$library" PYTHONPATH="$root/capi/python" PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg \
  /usr/bin/python3 "$root/docs/reference/python_reference.py" "$out/python"
echo "build-reference: $out/c/html/index.html and $out/python/jointcomp.html"
