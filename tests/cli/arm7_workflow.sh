#!/usr/bin/env bash
# A user's own seven-joint robot end to end (tests/data/arm7, docs/your-own-robot.md): a tracker export
# imported (joint_1..joint_7, measured = target + deviation), the import's refusals, kinematics of all seven
# joints, calibrate with the tool offset, every reported figure recomputed from the written URDF and
# parameter file alone, discover, and compensation with the calibrated robot (Python, when the library is
# given). A refused run leaves no --out folder behind.
# usage: arm7_workflow.sh JOINTCOMP_BINARY SOURCE_DIR SCRATCH_DIR [LIBJOINTCOMP]
set -euo pipefail
jointcomp="$1"
source_dir="$2"
work="$3"
library="${4:-}"
python=/usr/bin/python3
data="$source_dir/tests/data/arm7"
rm -rf "$work"
mkdir -p "$work"
fail() { echo "arm7_workflow: $*" >&2; exit 1; }
refused() {  # refused EXPECTED_TEXT COMMAND...: the command fails and its message names EXPECTED_TEXT
  local expected="$1"
  shift
  if "$@" >"$work/out.txt" 2>"$work/err.txt"; then fail "accepted: $*"; fi
  grep -c -- "$expected" "$work/err.txt" >/dev/null || fail "'$*' refused without naming '$expected': $(cat "$work/err.txt")"
}

# kinematics prints every joint's angle: 7 angles, 3 positions, 7 torques per pose row.
"$jointcomp" kinematics --urdf "$data/arm7.urdf" >"$work/kinematics.txt"
grep -c "7 joints" "$work/kinematics.txt" >/dev/null || fail "kinematics does not say 7 joints"
awk 'NR > 2 && NF != 17 { bad = 1 } END { exit bad }' "$work/kinematics.txt" ||
  fail "kinematics rows do not carry 7 angles and 7 torques: $(cat "$work/kinematics.txt")"

# The export: joint_1..joint_7 found by name, the measured position derived as target + deviation.
columns="t=Point,x=X_target+dX,y=Y_target+dY,z=Z_target+dZ"
"$jointcomp" import-csv --in "$data/tracker_export.csv" --out "$work/fit.csv" --columns "$columns" --robot arm7 \
  --target 10,-5,80 >"$work/import.txt"
grep -c "of 7 joints" "$work/import.txt" >/dev/null || fail "import-csv did not import 7 joints: $(cat "$work/import.txt")"
"$python" - "$work/fit.csv" "$data/campaign_fit.csv" <<'PY'
import sys
def read(path):
    meta = {l[2:].split(":")[0]: l.split(":", 1)[1].strip() for l in open(path) if l.startswith("# ")}
    rows = [l.strip().split(",") for l in open(path) if not l.startswith("#")]
    head = rows[0]
    return meta, [{c: float(v) for c, v in zip(head, r) if v} for r in rows[1:]]
meta, imported = read(sys.argv[1])
_, simulated = read(sys.argv[2])
assert meta["target"] == "10,-5,80" and meta["robot"] == "arm7", meta
assert len(imported) == len(simulated)
for a, b in zip(imported, simulated):
    for j in range(1, 8):
        assert abs(a[f"q{j}"] - b[f"q{j}"]) < 1e-4, (j, a, b)
    for c in "xyz":  # the export rounds the target to 1 um and the deviation to 0.1 um
        assert abs(a[c] - b[c]) < 1e-3, (c, a[c], b[c])
PY

# What the import refuses, each naming the fault.
# Joints named A1..A7 and mapped as q1..q6 only: A7 is not dropped silently.
sed '5s/joint_/A/g' "$data/tracker_export.csv" >"$work/a_names.csv"
six="q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,q6=A6,$columns"
refused "'A7' that looks like joint 7" "$jointcomp" import-csv --in "$work/a_names.csv" --out "$work/six.csv" \
  --columns "$six"
"$jointcomp" import-csv --in "$work/a_names.csv" --out "$work/six.csv" --columns "$six" --joints 6 \
  >/dev/null || fail "--joints 6 does not let the user import six joints on purpose"
refused "joints before it" "$jointcomp" import-csv --in "$work/a_names.csv" --out "$work/gap.csv" \
  --columns "q1=A1,q2=A2,q4=A4,$columns"
refused "mapped to both" "$jointcomp" import-csv --in "$data/tracker_export.csv" --out "$work/twice.csv" \
  --columns "t=Point,x=dX,y=dX,z=dZ"
sed '5s/dZ$/dX/' "$data/tracker_export.csv" >"$work/duplicate.csv"
refused "2 columns named 'dX'" "$jointcomp" import-csv --in "$work/duplicate.csv" --out "$work/dup.csv" \
  --columns "$columns"
refused "robot" "$jointcomp" import-csv --in "$data/tracker_export.csv" --out "$work/newline.csv" \
  --columns "$columns" --robot $'arm7\n# frame: instrument'
[ ! -e "$work/newline.csv" ] || fail "a refused import left its output behind"

# A refused run leaves no --out folder behind (here: a campaign that does not exist).
refused "missing.csv" "$jointcomp" calibrate --urdf "$data/arm7.urdf" --campaign "$work/missing.csv" \
  --out "$work/new/deeper"
[ ! -e "$work/new" ] || fail "a refused calibrate left its --out folder behind"

# calibrate: the tool offset from the campaign (10,-5,80 mm) is fitted; the held-out campaign improves.
"$jointcomp" calibrate --urdf "$data/arm7.urdf" --params "$data/arm7.json" --campaign "$work/fit.csv" \
  --holdout "$data/campaign_holdout.csv" --out "$work/calibrate" --no-plot --quiet >/dev/null
grep -c "held out, frame re-fitted\|frame fitted" "$work/calibrate/summary.txt" >/dev/null &&
  fail "summary.txt of a base-frame campaign speaks of a fitted frame"
# The tool offset kept at 0 on purpose: "before" and "after" both suffer from the missing 80 mm.
"$jointcomp" calibrate --urdf "$data/arm7.urdf" --params "$data/arm7.json" --campaign "$work/fit.csv" \
  --target 0,0,0 --fix target --out "$work/calibrate_no_tool" --no-plot --quiet >/dev/null
"$python" - "$work/calibrate" "$work/calibrate_no_tool" <<'PY'
import json, sys
report = json.load(open(sys.argv[1] + "/report.json"))
kept = json.load(open(sys.argv[2] + "/report.json"))
target = {p["name"]: p for p in report["parameters"] if p["name"].startswith("target.")}
for axis, true in zip("xyz", (10e-3, -5e-3, 80e-3)):
    p = target[f"target.{axis}_m"]
    assert p["identified"] and abs(p["value"] - true) < 1e-5, p
fit, held = report["campaigns"][0], report["campaigns"][1]
assert held["after"]["rms_mm"] < 0.2 * held["before"]["rms_mm"], held
assert "base frame" in held["role"], held["role"]
kept_target = {p["name"]: p for p in kept["parameters"] if p["name"].startswith("target.")}
assert all(not p["identified"] and p["value"] == 0.0 for p in kept_target.values()), kept_target
assert kept["campaigns"][0]["before"]["rms_mm"] > 10 * fit["before"]["rms_mm"], (kept["campaigns"][0], fit)
parameters = json.load(open(sys.argv[1] + "/parameters.json"))
tool = parameters["tool"]
assert tool["flange_link"] == "flange" and tool["link"] == "flange_target", tool
assert abs(tool["target_in_flange_m"][2] - 0.08) < 1e-5, tool
PY
grep -c '<link name="flange_target"/>' "$work/calibrate/arm7_calibrated.urdf" >/dev/null ||
  fail "the calibrated URDF has no tool link at the target"

# Every figure calibrate reported, recomputed from the written URDF and parameter file alone (the chain
# ends at the tool link; the offsets and stiffnesses are the parameter file's, the gravity torques the
# URDF's), and compensation with them.
if [ -n "$library" ]; then
  JOINTCOMP_LIBRARY="$library" PYTHONPATH="$source_dir/capi/python" "$python" - "$work/calibrate" "$work/fit.csv" \
    "$data/campaign_holdout.csv" <<'PY'
import json, sys
import numpy as np
import jointcomp
folder, fit_path, held_path = sys.argv[1:4]
report = json.load(open(folder + "/report.json"))
robot = jointcomp.Robot(folder + "/arm7_calibrated.urdf", folder + "/parameters.json")
assert robot.dof == 7
def rows(path):
    lines = [l.strip().split(",") for l in open(path) if not l.startswith("#")]
    head = lines[0]
    q = np.array([[float(r[head.index(f"q{j}")]) for j in range(1, 8)] for r in lines[1:]])
    p = np.array([[float(r[head.index(c)]) for c in "xyz"] for r in lines[1:]])
    return np.radians(q), p
parameters = json.load(open(folder + "/parameters.json"))
offset = np.array(next(e for e in parameters["effects"] if e["type"] == "offset")["offset_rad"])
stiffness = np.array(next(e for e in parameters["effects"] if e["type"] == "compliance")["stiffness_nm_per_rad"],
                     dtype=float)
def statistics(errors):
    return {"mean_mm": errors.mean(), "rms_mm": np.sqrt((errors ** 2).mean()), "max_mm": errors.max()}
for campaign, path in zip(report["campaigns"], (fit_path, held_path)):
    q, measured = rows(path)
    # The calibration's measurement model from the files: the offsets, and the compliance under the
    # calibrated URDF's gravity torques at the commanded pose.
    actual = q + offset - robot.gravity_torques(q) / stiffness
    recomputed = statistics(np.linalg.norm(robot.forward_kinematics(actual)[:, :3, 3] * 1e3 - measured, axis=1))
    for key, value in recomputed.items():
        assert abs(value - campaign["after"][key]) < 1e-6, (campaign["file"], key, value, campaign["after"][key])
    # The quasi-static robot of the library settles where the torque at the deflected pose balances: the
    # same figures to within a micrometre (the torque's change over the deflection).
    settled = q + robot.predict_joint_errors(q)
    again = statistics(np.linalg.norm(robot.forward_kinematics(settled)[:, :3, 3] * 1e3 - measured, axis=1))
    for key, value in again.items():
        assert abs(value - campaign["after"][key]) < 1e-3, (campaign["file"], key, value, campaign["after"][key])
# Compensation with the calibrated robot: the compensated command plus its predicted joint error is the plan.
planned = np.radians([[10, 30, -20, -60, 15, 40, 5], [-40, 50, 30, -80, -20, 60, -30]])
command, _ = robot.compensate(planned)
reached = command + robot.predict_joint_errors(command)
assert np.abs(reached - planned).max() < 1e-9, np.abs(reached - planned).max()
assert np.abs(command - planned).max() > 1e-5, "the compensation changed nothing"
PY
fi

# discover on the seven-joint arm: the textbook base, a step or two.
"$jointcomp" discover --urdf "$data/arm7.urdf" --params "$data/arm7.json" --campaign "$work/fit.csv" \
  --holdout "$data/campaign_holdout.csv" --max-steps 2 --types offset,compliance,nonlinear_compliance \
  --out "$work/discover" --no-plot --quiet >/dev/null
"$python" - "$work/discover" <<'PY'
import json, sys
report = json.load(open(sys.argv[1] + "/report.json"))
parameters = json.load(open(sys.argv[1] + "/parameters.json"))
assert parameters["robot"] == "arm7"
compliance = next(e for e in parameters["effects"] if e["type"] == "compliance")
assert len(compliance["stiffness_nm_per_rad"]) == 7, compliance
assert parameters["tool"]["link"] == "flange_target", parameters.get("tool")
assert abs(parameters["tool"]["target_in_flange_m"][2] - 0.08) < 1e-5, parameters["tool"]
PY
grep -c '<link name="flange_target"/>' "$work/discover/arm7_discovered.urdf" >/dev/null ||
  fail "the discovered URDF has no tool link at the target"
echo "arm7_workflow: ok"
