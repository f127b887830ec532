#!/usr/bin/env bash
# valgrind memcheck of the FMU importer test (tests/fmu/test_fmu_importer.cpp): any invalid access, use of
# uninitialised memory or leak fails.
#   valgrind-fmu.sh <build folder with the tests> [GoogleTest filter, default: the subset test.sh runs]
# The default subset exercises instantiate, initialise, step, get/set/serialise/deserialise state and
# free of both FMUs, and their misuse, in a few minutes; '*' runs everything (tests/load/run-load.sh).
set -euo pipefail
build="$1"
filter="${2:-*DescribesItself*:*CorruptOrForeignStatesAreRefused*:*RestoringAStateMidRunContinuesIdentically*:*BadStepsAreRefused*:FmuMisuse*:*CallsOutOfOrderAreRefusedAndLogged*}"
test_binary="$build/tests/fmu/test_fmu"
[ -x "$test_binary" ] || { echo "no $test_binary: build the tests first"; exit 1; }
# The test needs the unzipped FMUs (CTest's fixture): unzip them as it does.
ctest --test-dir "$build" -R '^fmu_unzip_fmi[23]$' --output-on-failure >/dev/null
# --errors-for-leak-kinds=definite,indirect: still-reachable blocks (the C++ runtime's pools) are no leak.
valgrind --tool=memcheck --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite,indirect \
  --show-leak-kinds=definite,indirect --track-origins=yes --num-callers=30 --quiet \
  "$test_binary" --gtest_filter="$filter" --gtest_brief=1
