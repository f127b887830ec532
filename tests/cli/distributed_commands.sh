#!/usr/bin/env bash
# jointcomp montecarlo and jointcomp fleet (cli/distributed_commands.cpp): --help exits 0, bad options exit 2
# with the command's usage, and both run end to end through Python and a local Dask cluster of one worker.
# usage: distributed_commands.sh JOINTCOMP_BINARY MODEL_DIR SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
model="$2"
work="$3"
fail() { echo "distributed_commands: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work/tmp"
cd "$work"
# The killed run below cannot remove its cluster's temporary folder: it stays here, not in /tmp.
export TMPDIR="$work/tmp"

for command in montecarlo fleet; do
  "$jointcomp" "$command" --help >help.txt || fail "$command --help exited $?"
  grep -q "Usage: jointcomp $command" help.txt || fail "$command --help printed no usage"
done

# Bad options: exit 2, the option named, the usage printed.
expect_usage() {
  local phrase="$1"
  shift
  local status=0
  "$jointcomp" "$@" >log.txt 2>&1 || status=$?
  [ "$status" -eq 2 ] || { cat log.txt; fail "jointcomp $* exited $status, expected 2"; }
  grep -qF -- "$phrase" log.txt || { cat log.txt; fail "jointcomp $*: no '$phrase' in the message"; }
  grep -qF -- "Usage: jointcomp $1" log.txt || { cat log.txt; fail "jointcomp $*: no usage"; }
}
expect_usage "--samples: '0' is out of range: it must be an integer from 1 to 10000000" montecarlo --samples 0
expect_usage "--samples: '1073741824' is out of range: it must be an integer from 1 to 10000000" montecarlo --samples 1073741824
expect_usage "--samples: '1e3' is not an integer" montecarlo --samples 1e3
expect_usage "--seed: '-1' is out of range" montecarlo --seed -1
expect_usage "--seed: '5x' is not a number" montecarlo --seed 5x
expect_usage "--timeout: 'nan' is not a finite number" fleet --campaign "$model/params/rx170.json" --timeout nan
expect_usage "--timeout: '0' is out of range: it must be greater than 0" montecarlo --timeout 0
expect_usage "--workers: '0' is out of range" montecarlo --workers 0
expect_usage "--scheduler: 'garbage' is not a scheduler address" montecarlo --scheduler garbage
expect_usage "--scheduler: 'http://host:8786' is not a scheduler address" fleet --campaign "$model/params/rx170.json" \
  --scheduler http://host:8786
expect_usage "--scheduler: 'tcp://host:99999' is not a scheduler address" montecarlo --scheduler tcp://host:99999
expect_usage "--report: File does not exist: absent.json" montecarlo --report absent.json
expect_usage "--report excludes --distribution" montecarlo --report "$model/params/rx170.json" --distribution "$model/params/rx170.json"
expect_usage "--campaign is required" fleet
expect_usage "--campaign: File does not exist: absent.csv" fleet --campaign absent.csv
expect_usage "--method: discovery not in" fleet --campaign "$model/params/rx170.json" --method discovery

# --out is checked before any work, by the C++ side (Python is not even started): a file, a /proc path and an
# empty path are refused at once, exit 1.
expect_refused() {
  local phrase="$1"
  shift
  local status=0
  "$jointcomp" "$@" >log.txt 2>&1 || status=$?
  [ "$status" -eq 1 ] || { cat log.txt; fail "jointcomp $* exited $status, expected 1"; }
  grep -qF -- "$phrase" log.txt || { cat log.txt; fail "jointcomp $*: no '$phrase' in the message"; }
  if grep -q "^wrote \|draw\|Dask" log.txt; then cat log.txt; fail "jointcomp $* worked before refusing"; fi
}
echo "not a folder" >a_file
expect_refused "--out: 'a_file' exists and is not a folder" montecarlo --samples 2 --out a_file
expect_refused "--out: '/proc/jointcomp-out' cannot be created" montecarlo --samples 2 --out /proc/jointcomp-out
expect_refused "--out: the path is empty" montecarlo --samples 2 --out ""
expect_refused "--out: 'a_file' exists and is not a folder" fleet --campaign "$model/params/rx170.json" --out a_file
expect_refused "--out: the path is empty" fleet --campaign "$model/params/rx170.json" --out ""

# A malformed report reaches Python, which names it (exit 1).
echo '{"format": "something else"}' >odd.json
status=0
"$jointcomp" montecarlo --report odd.json --samples 1 --workers 1 --out mc >log.txt 2>&1 || status=$?
[ "$status" -eq 1 ] && grep -q "not a report jointcomp knows" log.txt || { cat log.txt; fail "odd report: exit $status"; }

# End to end on one local worker: a small Monte Carlo and a fleet of two robots.
"$jointcomp" montecarlo --samples 2 --workers 1 --out mc >log.txt 2>&1 || { cat log.txt; fail "montecarlo failed"; }
grep -q "In 95 % of the draws the compensated path stays within" log.txt || { cat log.txt; fail "montecarlo printed no bound"; }
grep -q "too few for a 95 % confidence interval" log.txt || { cat log.txt; fail "2 draws gave no warning"; }
[ -s mc/montecarlo.json ] && [ -s mc/montecarlo.csv ] && [ -s mc/montecarlo_band.png ] || fail "montecarlo outputs missing"
for k in 1 2; do
  "$jointcomp" simulate --protocol random --truth "$model/params/rx170.json" --perturb "$k" --seed "$k" --count 30 \
    --out "robot$k.csv" >/dev/null
done
"$jointcomp" simulate --protocol random --truth "$model/params/rx170.json" --perturb 1 --seed 9 --count 20 \
  --out robot1_again.csv >/dev/null
expect_usage "expected CAMPAIGN=HELD_OUT.csv" fleet --campaign robot1.csv --holdout robot1_again.csv
expect_usage "no file absent.csv" fleet --campaign robot1.csv --holdout robot1.csv=absent.csv
"$jointcomp" fleet --campaign robot1.csv robot2.csv --holdout robot1.csv=robot1_again.csv --workers 1 --out fleet \
  >log.txt 2>&1 || { cat log.txt; fail "fleet failed"; }
grep -q "robot1_again" fleet/robot1/report.json || fail "robot1's report has no held-out campaign"
grep -q "Outliers: after-RMS above median" log.txt || { cat log.txt; fail "fleet printed no outlier rule"; }
for f in robot1/report.json robot2/calibrated.urdf fleet_summary.csv fleet_summary.json fleet.png; do
  [ -s "fleet/$f" ] || fail "fleet/$f missing"
done
# A client killed (SIGKILL) part-way resumes with --resume to the same bytes as a run never stopped.
"$jointcomp" montecarlo --samples 60 --batch 2 --workers 1 --out whole >log.txt 2>&1 || { cat log.txt; fail "whole run"; }
"$jointcomp" montecarlo --samples 60 --batch 2 --workers 1 --out killed >killed.txt 2>&1 &
runner=$!
for _ in $(seq 600); do [ -e killed/montecarlo.checkpoint.npz ] && break; sleep 0.1; done
kill -KILL "$runner" 2>/dev/null || true
wait "$runner" 2>/dev/null || true
[ -e killed/montecarlo.checkpoint.npz ] || { cat killed.txt; fail "no checkpoint before the kill"; }
[ ! -e killed/montecarlo.json ] || fail "the run finished before it was killed: nothing to resume"
status=0
"$jointcomp" montecarlo --samples 60 --batch 2 --workers 1 --out killed >log.txt 2>&1 || status=$?
[ "$status" -eq 1 ] && grep -q "add --resume to continue it" log.txt || { cat log.txt; fail "a checkpoint was overwritten"; }
"$jointcomp" montecarlo --samples 60 --batch 5 --workers 1 --out killed --resume >log.txt 2>&1 ||
  { cat log.txt; fail "resume failed"; }
for f in montecarlo.json montecarlo.csv montecarlo_band.png; do
  cmp -s "whole/$f" "killed/$f" || fail "the resumed $f differs from the uninterrupted one"
done
[ ! -e killed/montecarlo.checkpoint.npz ] || fail "the checkpoint was left behind"
[ ! -e dask-worker-space ] || fail "dask-worker-space left in the working folder"

# Ctrl-C (SIGINT to the whole process group, as a terminal sends it) stops the run cleanly: exit 130, one
# message naming the checkpoint, no traceback, the cluster's temporary folder removed.
# (Each run first removes the folders of runs whose process is gone, the killed run's above among them: the
# check is that no folder is added, not that the count stays.)
before=$(ls "$TMPDIR")
# (A background job of a script starts with SIGINT ignored: the run is started with it restored, as in a terminal.)
setsid /usr/bin/python3 -c 'import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])' \
  "$jointcomp" montecarlo --samples 200 --batch 2 --workers 1 --out interrupted >log.txt 2>&1 &
runner=$!
for _ in $(seq 600); do [ -e interrupted/montecarlo.checkpoint.npz ] && break; sleep 0.1; done
kill -INT -- "-$runner"
status=0
wait "$runner" || status=$?
[ "$status" -eq 130 ] || { cat log.txt; fail "Ctrl-C: exit $status, expected 130"; }
grep -q "interrupted; .* draws are kept in interrupted/montecarlo.checkpoint.npz" log.txt || { cat log.txt; fail "Ctrl-C: no message"; }
if grep -q "Traceback" log.txt; then cat log.txt; fail "Ctrl-C printed a traceback"; fi
added=$(comm -13 <(echo "$before") <(ls "$TMPDIR"))
[ -z "$added" ] || fail "Ctrl-C left a temporary folder in $TMPDIR: $added"

echo "distributed_commands: all checks passed"
