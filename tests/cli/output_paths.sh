#!/usr/bin/env bash
# --out is checked before any work and every output goes under it: a file, a folder that cannot be made
# or a read-only file system is refused at once with the option, the path and the reason (exit code 1,
# nothing written), and `jointcomp paper` puts its FMUs in <out>/fmu, never in ./out.
# usage: output_paths.sh JOINTCOMP_BINARY MODEL_DIR SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
model="$2"
work="$3"
fail() { echo "output_paths: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cd "$work"

# Runs jointcomp with the arguments given; it must fail with exit code 1 and say every expected phrase.
# usage: refused "phrase1|phrase2" args...
refused() {
  local phrases="$1"
  shift
  local status=0
  "$jointcomp" "$@" >log.txt 2>&1 || status=$?
  [ "$status" -eq 1 ] || { cat log.txt; fail "jointcomp $* exited $status, expected 1"; }
  local phrase
  IFS='|' read -r -a wanted <<<"$phrases"
  for phrase in "${wanted[@]}"; do
    grep -qF -- "$phrase" log.txt || { cat log.txt; fail "jointcomp $*: no '$phrase' in the message"; }
  done
  if grep -q "^wrote \|Table II\|run 1/3" log.txt; then cat log.txt; fail "jointcomp $* worked before refusing"; fi
}

echo "not a folder" >a_file
refused "--out: 'a_file' exists and is not a folder" paper --quasi-static --out a_file --no-plot
refused "cannot be created" paper --quasi-static --out a_file/below --no-plot
refused "--out: '/proc/jointcomp-out' cannot be created" paper --quasi-static --out /proc/jointcomp-out --no-plot
"$jointcomp" simulate --protocol random --count 30 --urdf "$model/robots/rx170.urdf" \
  --truth "$model/params/rx170.json" --out campaign.csv >log.txt 2>&1 || { cat log.txt; fail "simulate failed"; }
refused "--out: 'a_file' exists and is not a folder" calibrate --urdf "$model/robots/rx170.urdf" \
  --params "$model/params/rx170.json" --campaign campaign.csv --out a_file --no-plot
refused "--out: 'a_file' exists and is not a folder" discover --urdf "$model/robots/rx170.urdf" \
  --params "$model/params/rx170.json" --campaign campaign.csv --out a_file --no-plot
refused "--out: 'a_file' exists and is not a folder" identify stiffness --campaign campaign.csv --out a_file --no-plot
mkdir -p a_folder
refused "--out: 'a_folder' is a folder, not a file" simulate --protocol random --urdf "$model/robots/rx170.urdf" \
  --truth "$model/params/rx170.json" --out a_folder
refused "cannot write 'a_file/c.csv'" simulate --protocol random --urdf "$model/robots/rx170.urdf" \
  --truth "$model/params/rx170.json" --out a_file/c.csv
refused "cannot write '/proc/x.csv'" import-ipa --in campaign.csv --out /proc/x.csv

# Everything `paper` writes lands under --out, the FMUs in its fmu folder.
"$jointcomp" paper --quasi-static --out results/paper --no-plot >log.txt 2>&1 || { cat log.txt; fail "paper failed"; }
[ -s results/paper/spiral_runs.csv ] && [ -s results/paper/summary.json ] || fail "paper wrote no results"
if grep -q "^wrote .*\.fmu" log.txt; then
  [ -s results/paper/fmu/jointcomp_fmi2.fmu ] && [ -s results/paper/fmu/jointcomp_fmi3.fmu ] ||
    fail "the FMUs are not in <out>/fmu"
fi
[ ! -e out ] || { ls -R out; fail "paper wrote into ./out although --out said otherwise"; }
# A name from the user's data never leads outside --out: a robot named "../../victim" in its URDF made
# calibrate write <out>/../../victim_calibrated.urdf.
mkdir -p victim_home/a/b
sed 's|<robot name="rx170">|<robot name="../../victim">|' "$model/robots/rx170.urdf" >victim.urdf
sed 's|"robot": "rx170"|"robot": "../../victim"|' "$model/params/rx170.json" >victim.json
"$jointcomp" simulate --protocol random --count 30 --urdf victim.urdf --truth victim.json --out victim.csv \
  >log.txt 2>&1 || { cat log.txt; fail "simulate of the victim robot failed"; }
"$jointcomp" calibrate --urdf victim.urdf --params victim.json --campaign victim.csv --out victim_home/a/b \
  --no-plot --quiet >log.txt 2>&1 || { cat log.txt; fail "calibrate of the victim robot failed"; }
[ -s victim_home/a/b/_.._victim_calibrated.urdf ] || { ls -R victim_home; fail "no _.._victim_calibrated.urdf"; }
[ "$(ls victim_home)" = a ] && [ "$(ls victim_home/a)" = b ] || { ls -R victim_home; fail "calibrate wrote outside --out"; }

echo "output_paths: bad --out refused before any work; outputs under --out"
