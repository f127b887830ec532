#!/usr/bin/env bash
# The FMU's chain of a ROS-Industrial-layout URDF: with --tip-link flange, export-fmu writes the plain RX170's
# resources/robot.json byte for byte; by default it ends at tool0; an unknown tip is refused with its name.
# usage: check_chain.sh SCRATCH JOINTCOMP PLAIN_URDF ROS_INDUSTRIAL_URDF PARAMETERS
set -euo pipefail
scratch="$1" tool="$2" plain="$3" ros="$4" params="$5"
fail() { echo "check_chain: $*" >&2; exit 1; }
rm -rf "$scratch" && mkdir -p "$scratch"
robot_json() {  # robot_json FMU DIR: unzips the FMU's resources/robot.json into DIR
  mkdir -p "$2" && (cd "$2" && cmake -E tar xf "$1" resources/robot.json)
}
"$tool" export-fmu --urdf "$plain" --params "$params" --out "$scratch/plain.fmu" >/dev/null
"$tool" export-fmu --urdf "$ros" --params "$params" --tip-link flange --out "$scratch/flange.fmu" >/dev/null
"$tool" export-fmu --urdf "$ros" --params "$params" --out "$scratch/tool0.fmu" >/dev/null
for name in plain flange tool0; do robot_json "$scratch/$name.fmu" "$scratch/$name"; done
cmp -s "$scratch/plain/resources/robot.json" "$scratch/flange/resources/robot.json" ||
  fail "the flange chain differs from the plain RX170"
grep -q '"tip_link": *"tool0"' "$scratch/tool0/resources/robot.json" || fail "the default chain does not end at tool0"
if "$tool" export-fmu --urdf "$ros" --params "$params" --tip-link gripper --out "$scratch/x.fmu" 2>"$scratch/err.txt"; then
  fail "an unknown tip link was accepted"
fi
grep -q "gripper" "$scratch/err.txt" || fail "the unknown tip is not named: $(cat "$scratch/err.txt")"
[ ! -e "$scratch/x.fmu" ] || fail "a refused export left a file behind"
echo "check_chain: export-fmu follows --base-link and --tip-link"
