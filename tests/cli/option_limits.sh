#!/usr/bin/env bash
# Every numeric option of every command is read whole, range-checked and refused naming the option and the
# value, before any work (exit 2): numbers were read by prefix ("--seed 1e3" ran seed 1, "--folds 5x" five
# folds), "--seed -1" became 2^64 - 1, nan passed every check, and unbounded counts ran until memory ran out.
# A campaign measured on another robot is refused by calibrate (exit 1).
# usage: option_limits.sh JOINTCOMP_BINARY MODEL_DIR SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
model="$2"
work="$3"
fail() { echo "option_limits: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cd "$work"

# refused STATUS PHRASE ARGS...: jointcomp must exit with STATUS at once, say PHRASE and write nothing.
refused() {
  local status_wanted="$1" phrase="$2"
  shift 2
  local status=0
  timeout 60 "$jointcomp" "$@" >log.txt 2>&1 || status=$?
  [ "$status" -eq "$status_wanted" ] || { cat log.txt; fail "jointcomp $* exited $status, expected $status_wanted"; }
  grep -qF -- "$phrase" log.txt || { cat log.txt; fail "jointcomp $*: no '$phrase' in the message"; }
  if grep -q "^wrote \|Table II\|run 1/3" log.txt; then cat log.txt; fail "jointcomp $* worked before refusing"; fi
}

urdf="$model/robots/rx170.urdf"
params="$model/params/rx170.json"
"$jointcomp" simulate --protocol random --count 30 --urdf "$urdf" --truth "$params" --out rx170.csv >log.txt 2>&1 ||
  { cat log.txt; fail "simulate failed"; }

refused 2 "--seed: '1e3' is not an integer" paper --quasi-static --seed 1e3 --out o --no-plot
refused 2 "--seed: '-1' is out of range: it must be an integer from 0 to 4611686018427387904" \
  paper --quasi-static --seed -1 --out o --no-plot
refused 2 "--feed-rate: '1e-5' is out of range: it must be from 0.003 to 2" \
  paper --quasi-static --feed-rate 1e-5 --out o --no-plot
refused 2 "--compensate-joints: '0' is out of range" paper --quasi-static --compensate-joints 0,2 --out o --no-plot
refused 2 "--loss-scale-mm: 'nan' is not a finite number" calibrate --urdf "$urdf" --params "$params" \
  --campaign rx170.csv --loss-scale-mm nan --out o --no-plot
for scale in -1 0; do
  refused 2 "--loss-scale-mm: '$scale' is out of range: it must be greater than 0" calibrate --urdf "$urdf" \
    --params "$params" --campaign rx170.csv --loss-scale-mm "$scale" --out o --no-plot
done
refused 2 "--folds: '5x' is not a number" discover --urdf "$urdf" --params "$params" --campaign rx170.csv \
  --folds 5x --out o --no-plot
refused 2 "--folds: '300' is out of range: it must be an integer from 2 to 20" discover --urdf "$urdf" \
  --params "$params" --campaign rx170.csv --folds 300 --out o --no-plot
refused 2 "--folds: 10 folds need at least 50 rows; the fitted campaigns have 30" discover --urdf "$urdf" \
  --params "$params" --campaign rx170.csv --folds 10 --out o --no-plot
refused 2 "--orders: '100000000' is out of range: it must be an integer from 1 to 64" discover --urdf "$urdf" \
  --params "$params" --campaign rx170.csv --orders 100000000 --out o --no-plot
refused 2 "--min-cv-gain: 'nan' is not a finite number" discover --urdf "$urdf" --params "$params" \
  --campaign rx170.csv --min-cv-gain nan --out o --no-plot
refused 2 "--cycles: '1e9' is not an integer" simulate --protocol back-and-forth --truth "$params" --cycles 1e9 --out o.csv
refused 2 "--cycles: '1000000000' is out of range: it must be an integer from 1 to 10000" \
  simulate --protocol back-and-forth --truth "$params" --cycles 1000000000 --out o.csv
refused 2 "--count: '2000000000' is out of range: it must be an integer from 1 to 100000" \
  simulate --protocol random --truth "$params" --count 2000000000 --out o.csv
refused 2 "--settle: 'inf' is not a finite number" simulate --protocol joint2-sweep --truth "$params" --settle inf --out o.csv
refused 2 "--joint: '2.5' is not an integer" identify transmission --campaign rx170.csv --joint 2.5 --out o
# Within the options' ranges, the experiment still refuses more rows than it makes.
refused 1 "steps are more than 1000000 rows" \
  simulate --protocol back-and-forth --truth "$params" --cycles 10000 --out o.csv
[ ! -e o.csv ] || fail "a refused simulate wrote o.csv"

# A campaign of another robot: calibrate --urdf ur10.urdf on a campaign of rx170 "calibrated" the UR10.
refused 1 "the campaign is of robot 'rx170', the model of 'ur10'" calibrate --urdf "$model/robots/ur10.urdf" \
  --campaign rx170.csv --out o --no-plot --quiet
echo "option_limits: every numeric option read whole and range-checked; campaigns of another robot refused"
