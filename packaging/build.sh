#!/usr/bin/env bash
# Installs the dependencies (idempotent) and builds jointcomp in build/<name> with CMake.
# usage: packaging/build.sh [build-name] [extra cmake arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash packaging/install-deps.sh
name="${1:-release}"
mkdir -p build
shift || true
cmake -S . -B "build/$name" -DCMAKE_BUILD_TYPE=Release "$@" >"build/$name.configure.log" 2>&1 || {
  cat "build/$name.configure.log"; exit 1; }
rm -f "build/$name.configure.log"
cmake --build "build/$name" -j"$(nproc)"
