#!/usr/bin/env bash
# A fresh clone with nothing beside it: the tests that need data the repository does not carry skip, and
# say what is missing and where, whether JOINTCOMP_SHARED is unset or points at the wrong folder.
#   check_shared_skips.sh <test_io executable> <tests/fmu/check_schema.sh> <a modelDescription.xml>
set -euo pipefail
test_io="$1" check_schema="$2" description="$3"
fail() { echo "FAILED: $*"; exit 1; }

out=$(env -u JOINTCOMP_SHARED "$test_io" --gtest_filter=IpaImport.SeriesA 2>&1) || fail "the test failed: $out"
echo "$out" | grep -F "skipped: the IPA UR10 data not found: JOINTCOMP_SHARED is not set" ||
  fail "no named skip without the setting: $out"
echo "$out" | grep -cF "[  SKIPPED ]" >/dev/null || fail "not reported as skipped: $out"

out=$(JOINTCOMP_SHARED=/nonexistent/shared "$test_io" --gtest_filter=IpaImport.SeriesA 2>&1) || fail "$out"
echo "$out" | grep -F "skipped: the IPA UR10 data not found at /nonexistent/shared/data/ipa-ur10/Series_A/measurements_grid.csv" ||
  fail "no named skip with a wrong folder: $out"

set +e
out=$(env -u JOINTCOMP_SHARED bash "$check_schema" 2 "$description" 2>&1)
status=$?
set -e
[ "$status" = 77 ] || fail "check_schema.sh exited $status without the setting, not 77 (skip): $out"
echo "$out" | grep -F "skipped: the FMI 2 schema not found: JOINTCOMP_SHARED is not set" || fail "$out"
echo "the skips are named"
