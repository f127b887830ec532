#!/usr/bin/env bash
# Runs clang-tidy (.clang-tidy at the root) on jointcomp's own sources in model, capi, fmu and cli, with
# the compile commands of a build folder (default build/test: run `bash test.sh plain` or
# `cmake --preset test` first). Slow (Eigen is heavy to parse): about half a minute per file per core.
# usage: packaging/tidy.sh [BUILD_DIR] [JOBS]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/test}"
jobs="${2:-$(nproc)}"
[ -f "$build/compile_commands.json" ] || { echo "tidy.sh: no $build/compile_commands.json (configure a build first)" >&2; exit 2; }
command -v run-clang-tidy >/dev/null || { echo "tidy.sh: run-clang-tidy is missing (bash packaging/install-deps.sh)" >&2; exit 2; }
run-clang-tidy -p "$build" -j "$jobs" -quiet "$PWD/(model|capi/src|fmu|cli)/.*\.cpp$"
