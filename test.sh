#!/usr/bin/env bash
# Sets everything up and runs every test, in three builds of their own, each configured by its preset of
# CMakePresets.json (test, asan, tsan: the one place their options are written):
#   1. build/test (GCC, Release): the whole CTest suite, then valgrind memcheck of the FMU importer test
#      (a subset that exercises every phase of both FMUs).
#   2. build/asan (clang, AddressSanitizer + UndefinedBehaviorSanitizer, with libFuzzer's coverage): the
#      suite again (but for what cannot run there, see below), then each fuzz target for
#      JOINTCOMP_FUZZ_SECONDS from its committed corpus, and the inputs that once crashed one.
#   3. build/tsan (GCC, ThreadSanitizer): the C API's threads test (two handles in two threads, no race).
# usage: bash test.sh [plain|asan|fuzz|tsan]   (no argument: every stage, in that order; asan runs the suite
# under the sanitizers, fuzz builds the same folder and runs only the fuzz targets)
# Each stage prints what it cost. JOINTCOMP_TEST_DIR, JOINTCOMP_ASAN_DIR and JOINTCOMP_TSAN_DIR choose
# other build folders, JOINTCOMP_ASAN_CC and JOINTCOMP_ASAN_CXX other clang drivers (for a developer who
# keeps several builds).
set -euo pipefail
cd "$(dirname "$0")"
test_dir="${JOINTCOMP_TEST_DIR:-build/test}"
asan_dir="${JOINTCOMP_ASAN_DIR:-build/asan}"
tsan_dir="${JOINTCOMP_TSAN_DIR:-build/tsan}"
fuzz_seconds="${JOINTCOMP_FUZZ_SECONDS:-15}"
jobs="$(nproc)"
stages=(plain asan fuzz tsan)
if [ $# -gt 1 ] || { [ $# -eq 1 ] && [[ ! " ${stages[*]} " =~ " $1 " ]]; }; then
  echo "usage: bash test.sh [plain|asan|fuzz|tsan]   (no argument: all of them; unknown: '$*')" >&2
  exit 2
fi
if [ $# -eq 1 ]; then stages=("$1"); fi

stage_start=$SECONDS
stage() {  # prints the cost of the stage that just ended
  echo "test.sh: $1 took $(((SECONDS - stage_start) / 60)) min $(((SECONDS - stage_start) % 60)) s"
  stage_start=$SECONDS
}
configure() {  # configure <build folder> <cmake arguments...>, quiet unless it fails
  local dir="$1"
  shift
  mkdir -p "$(dirname "$dir")"
  cmake -S . -B "$dir" "$@" >"$dir.configure.log" 2>&1 || { cat "$dir.configure.log"; exit 1; }
  rm -f "$dir.configure.log"
}

bash packaging/install-deps.sh  # installs only what is missing

plain_stage() {
  # 1. The plain build.
  configure "$test_dir" --preset test
  cmake --build "$test_dir" -j"$jobs"
  stage "build ($test_dir)"
  ctest --test-dir "$test_dir" --no-tests=error --output-on-failure --timeout 900 -j"$jobs"
  stage "tests ($test_dir)"
  # valgrind memcheck of the FMU importer test on a subset that instantiates, initialises, steps, gets, sets,
  # serialises and frees both FMUs and misuses them (the whole test: tests/load/run-load.sh).
  bash tests/load/valgrind-fmu.sh "$test_dir"
  stage "valgrind memcheck of the FMU importer test ($test_dir)"
}

asan_build() {
  # 2. AddressSanitizer and UndefinedBehaviorSanitizer (any undefined behaviour fails the test), one build
  # that also carries the fuzz targets: the libraries are compiled with libFuzzer's coverage
  # (fuzzer-no-link) so that the fuzzers see into them. -O1 as the sanitizers recommend, with line tables
  # for readable reports.
  configure "$asan_dir" --preset asan \
    "-DCMAKE_C_COMPILER=${JOINTCOMP_ASAN_CC:-clang}" "-DCMAKE_CXX_COMPILER=${JOINTCOMP_ASAN_CXX:-clang++}" \
    "-DJOINTCOMP_FUZZ_SECONDS=$fuzz_seconds"
  cmake --build "$asan_dir" -j"$jobs"
  stage "build ($asan_dir)"
}

asan_stage() {
  # Not run under the sanitizers (each named below runs in build 1):
  # - fmu_binary_fmi*: they check the NEEDED entries and exports of the release FMU binary; a sanitized
  #   binary refers to the sanitizer runtime by design;
  # - io_kill_during_write: kills the tool at moments measured on an uninstrumented run, twenty times;
  # - capi_threads: the threads test, run under ThreadSanitizer in build 3;
  # - limits_function_sizes (and its own check, _catches): they read the sources with clang-tidy, not
  #   instrumented code, at a core-minute or more a run;
  # - cli_workflow: runs a Python example that loads the library into Debian's uninstrumented interpreter
  #   (the Python tests of tests/capi are not even registered in a sanitizer build);
  # - what takes from ten seconds to five minutes instrumented (20 to 80 times its plain time) and repeats
  #   code paths that faster tests cover here: sweeps over seeds and data sets (discovery, calibration and
  #   identification statistics), the paper's 30 s spiral run again and again (at fine steps through the
  #   FMUs, through the plant and the C API), the plant's energy over a long horizon, two FMU instances in
  #   threads, the dynamic correction (its refinement runs the plant ten or more times), and the FMI 2 twin of two slow FMU tests whose FMI 3 version runs here (the versions share
  #   the instance); the paper identification's repeats (each identification 20 to 80 times its 0.6 s; one
  #   identification and its refit run here in PaperIdentification.IdentifiedModelLeavesLessThanTheNominalOne).
  #   The FMU state is fuzzed here too (fmu_state).
  slow_under_sanitizers='TheDynamicCorrectionFollowsTheSpiral|DiscoveryTables\.|Discovery\.BacklashAndHysteresisAreToldApart|DiscoveryPeriodic\.SmoothnessPriorBridgesTheGapsOfAGrid|OfflineDynamicReferences|DynamicCompensation\.WithTheModelEqualToTheRobot|DiscoverySweep\.|DiscoveryIpaUr10\.|FmuOfTheUr10\.|IpaUr10Calibration\.|IntervalsCoverTheTruth|OverSeeds|SpiralAt1ms|FmuRegression\.|VaryingCommunicationSteps|RegressionThroughTheFmuEqualsTheCApi|PlantEnergy\.ConservedWithoutLossesOrControl|CapiMatchesCore\.SpiralPlanTrajectoryCompensationAndExperiment|Discovery\.RaRzOnHeldOutSpiral|TwoInstancesInTwoThreads|SpiralExperiment\.(ADifferentNoiseSeed|RunsAreCompleteAndNamed|DefaultSpecReproduces)|PlantSpiralRegression\.(MetricsFollowFromTheErrors|CorrectionRemovesMostOfRa)|PlantMisuse\.AbsurdGains|PaperIdentification\.(SameSeedSameBits|TheSweepReveals|Joint2Harmonics)|(RestoringAStateMidRunContinuesIdentically|BadStepsAreRefused)/fmi2'
  # JOINTCOMP_ASAN_ALL=1 runs the slow ones under the sanitizers too (each takes 10 s to 5 min there).
  if [ "${JOINTCOMP_ASAN_ALL:-0}" = 1 ]; then
    not_under_sanitizers="^fmu_binary_fmi[23]$|^io_kill_during_write$|^capi_threads$|^cli_workflow$|^limits_function_sizes(_catches)?$"
  else
    not_under_sanitizers="^fmu_binary_fmi[23]$|^io_kill_during_write$|^capi_threads$|^cli_workflow$|^limits_function_sizes(_catches)?$|$slow_under_sanitizers"
  fi
  sanitizer_environment
  ctest --test-dir "$asan_dir" --no-tests=error --output-on-failure --timeout 900 -j"$jobs" -LE fuzz \
    -E "$not_under_sanitizers"
  stage "tests under ASan+UBSan ($asan_dir)"
  unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS
}

sanitizer_environment() {
  export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0"
}

fuzz_stage() {
  # Two fuzz targets at a time, each for JOINTCOMP_FUZZ_SECONDS, from their committed corpora.
  sanitizer_environment
  ctest --test-dir "$asan_dir" --no-tests=error --output-on-failure --timeout 600 -j"$jobs" -L fuzz
  stage "fuzzing, ${fuzz_seconds} s per target ($asan_dir)"
  unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS
}

tsan_stage() {
  # 3. ThreadSanitizer, with only the target it needs (-O1 as TSan recommends).
  configure "$tsan_dir" --preset tsan
  cmake --build "$tsan_dir" -j"$jobs" --target test_capi_threads
  ctest --test-dir "$tsan_dir" -R '^capi_threads$' --no-tests=error --output-on-failure --timeout 600
  stage "threads test under TSan ($tsan_dir)"
}

asan_built=0
for stage_name in "${stages[@]}"; do
  case "$stage_name" in
    plain) plain_stage ;;
    asan | fuzz)
      if [ "$asan_built" = 0 ]; then asan_build; asan_built=1; fi
      "${stage_name}_stage" ;;
    tsan) tsan_stage ;;
  esac
done
