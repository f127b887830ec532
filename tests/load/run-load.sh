#!/usr/bin/env bash
# Load tests (minutes; not part of test.sh), in a Release build with the tests (default build/test, as
# test.sh leaves it; built here if needed):
#   1. an hour of simulated time through each FMU, twice per FMI version: resident memory flat after a
#      warm-up, outputs identical bit for bit between the runs and the versions (tests/load/fmu_load.cpp);
#   2. a million-point trajectory through jc_compensate_trajectory, three times: references identical,
#      memory flat (tests/load/capi_load.c);
#   3. valgrind memcheck of the whole FMU importer test (instantiate, step, get/set/serialise state and
#      free both FMUs, and every misuse): no error, no leak.
# usage: tests/load/run-load.sh [build folder] [simulated seconds per FMU run, default 3600]
set -euo pipefail
cd "$(dirname "$0")/../.."
build="${1:-build/test}"
seconds="${2:-3600}"
bash packaging/install-deps.sh
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DJOINTCOMP_BUILD_BENCH=OFF -DJOINTCOMP_BUILD_TESTS=ON >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target fmu_load capi_load test_fmu

echo "== 1. FMUs: $seconds s of simulated time per run"
time "$build/tests/load/fmu_load" "$PWD/$build/fmu/jointcomp_fmi2" "$PWD/$build/fmu/jointcomp_fmi3" "$seconds"

echo "== 2. C API: a million-point trajectory"
time "$build/tests/load/capi_load" model/robots/rx170.urdf model/params/rx170.json 1000000

echo "== 3. valgrind memcheck of the FMU importer test"
bash tests/load/valgrind-fmu.sh "$build" '*'
