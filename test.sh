#!/usr/bin/env bash
# Sets everything up, builds jointcomp with its tests and runs every test.
set -euo pipefail
cd "$(dirname "$0")"
bash packaging/build.sh test -DJOINTCOMP_BUILD_BENCH=OFF -DJOINTCOMP_BUILD_TESTS=ON
cd build/test
ctest --no-tests=error --output-on-failure --timeout 900 -j"$(nproc)"
