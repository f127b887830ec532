#!/usr/bin/env bash
# Sets everything up and runs jointcomp's main job on its built-in default data (the Staubli RX170).
set -euo pipefail
cd "$(dirname "$0")"
bash packaging/build.sh release -DJOINTCOMP_BUILD_BENCH=OFF -DJOINTCOMP_BUILD_TESTS=OFF
./build/release/cli/jointcomp "$@"
