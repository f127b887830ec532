#!/usr/bin/env bash
# The FMU's chain of a ROS-Industrial-layout URDF: with --tip-link=flange the build tool writes the plain
# RX170's robot.json byte for byte; by default it ends at tool0; an unknown tip fails the build.
# usage: check_chain.sh SCRATCH RESOURCES_TOOL PLAIN_URDF ROS_INDUSTRIAL_URDF PARAMETERS
set -euo pipefail
scratch="$1" tool="$2" plain="$3" ros="$4" params="$5"
fail() { echo "check_chain: $*" >&2; exit 1; }
mkdir -p "$scratch"
"$tool" "$plain" "$params" "$scratch/plain.json" "$scratch/v1.json"
"$tool" "$ros" "$params" "$scratch/flange.json" "$scratch/v2.json" --tip-link=flange
cmp -s "$scratch/plain.json" "$scratch/flange.json" || fail "the flange chain differs from the plain RX170"
"$tool" "$ros" "$params" "$scratch/tool0.json" "$scratch/v3.json"
grep -q '"tip_link": *"tool0"' "$scratch/tool0.json" || fail "the default chain does not end at tool0"
if "$tool" "$ros" "$params" "$scratch/x.json" "$scratch/v4.json" --tip-link=gripper 2>"$scratch/err.txt"; then
  fail "an unknown tip link was accepted"
fi
grep -q "tip link 'gripper' does not exist" "$scratch/err.txt" || fail "the unknown tip is not named"
echo "check_chain: the FMU's chain follows --base-link and --tip-link"
