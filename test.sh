#!/usr/bin/env bash
# Sets everything up, builds jointcomp with its tests and runs every test; then builds the C API's
# threads test under ThreadSanitizer and runs it (two handles in two threads, no data race).
set -euo pipefail
cd "$(dirname "$0")"
bash packaging/build.sh test -DJOINTCOMP_BUILD_BENCH=OFF -DJOINTCOMP_BUILD_TESTS=ON
ctest --test-dir build/test --no-tests=error --output-on-failure --timeout 900 -j"$(nproc)"

# ThreadSanitizer, in a build of its own with only the target it needs (-O1 as TSan recommends).
cmake -S . -B build/tsan -DCMAKE_BUILD_TYPE=Release "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG" \
  "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" -DJOINTCOMP_BUILD_BENCH=OFF -DJOINTCOMP_SANITIZE=thread \
  >build/tsan.configure.log 2>&1 || { cat build/tsan.configure.log; exit 1; }
cmake --build build/tsan -j"$(nproc)" --target test_capi_threads
ctest --test-dir build/tsan -R '^capi_threads$' --no-tests=error --output-on-failure --timeout 600
