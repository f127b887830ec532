#!/usr/bin/env bash
# The command-line tool end to end, as a user drives it: simulate campaigns from a truth the nominal model
# lacks (a joint-3 offset), identify, calibrate and discover on them, and check what the written reports
# say against that truth; then the errors a user makes, each refused with a message that names it.
# usage: cli_workflow.sh JOINTCOMP_BINARY DATA_DIR (model/) SCRATCH_DIR [LIBJOINTCOMP]
set -euo pipefail
jointcomp="$1"
data="$2"
work="$3"
library="${4:-}"
python=/usr/bin/python3
rm -rf "$work"
mkdir -p "$work"
urdf="$data/robots/rx170.urdf"
params="$data/params/rx170.json"
fail() { echo "cli_workflow: $*" >&2; exit 1; }

# grep -c, not grep -q: -q stops at the first match, and under pipefail the writer's SIGPIPE then fails the
# pipe at random (seen in CI); -c reads everything.
help_text=$("$jointcomp" help)
for type in offset compliance nonlinear_compliance harmonic backlash hysteresis thermal geometric payload periodic \
  instrument_scale link_bending; do
  grep -c "\b$type\b" <<<"$help_text" >/dev/null || fail "help does not list the discovery type $type"
done

# A joint-2 sweep while the robot warms up: the temperature column rises.
"$jointcomp" simulate --protocol joint2-sweep --truth "$params" --seed 3 --step 0.2 --warm-up 5,600 \
  --out "$work/sweep.csv" >/dev/null
"$python" - "$work/sweep.csv" <<'PY'
import sys
rows = [l.strip().split(",") for l in open(sys.argv[1]) if not l.startswith("#")]
column = rows[0].index("temp")
temps = [float(r[column]) for r in rows[1:]]
assert temps[-1] > temps[0] + 1.0, (temps[0], temps[-1])
assert all(b >= a for a, b in zip(temps, temps[1:])), "the warm-up is monotonic"
PY

"$jointcomp" identify transmission --campaign "$work/sweep.csv" --params "$params" --out "$work/transmission" \
  --no-plot >/dev/null
"$python" - "$work/transmission/report.json" "$params" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
truth = json.load(open(sys.argv[2]))
found = {h["cycles_per_revolution"]: h for h in report["harmonics"] if h["significant"]}
true = {h["cycles_per_revolution"]: h for e in truth["effects"] if e["type"] == "transmission_error"
        for h in e["harmonics"] if h["joint"] == "joint_2" and h["of"] == "stage_2"}
assert set(found) == set(true), (sorted(found), sorted(true))
for order, h in found.items():
    assert abs(h["amplitude_deg"] - true[order]["amplitude_deg"]) < 4 * h["amplitude_se_deg"], order
PY

# The truth carries a joint-3 offset of 1 mrad that rx170.json does not know.
"$python" - "$params" "$work/truth.json" <<'PY'
import json, sys
document = json.load(open(sys.argv[1]))
document["effects"].append({"type": "offset", "offset_rad": [0, 0, 1e-3, 0, 0, 0]})
json.dump(document, open(sys.argv[2], "w"), indent=2)
PY
"$jointcomp" simulate --protocol random --truth "$work/truth.json" --seed 5 --count 150 --out "$work/fit.csv" >/dev/null
"$jointcomp" simulate --protocol random --truth "$work/truth.json" --seed 6 --count 60 --out "$work/held.csv" >/dev/null
cp "$work/fit.csv" "$work/fit.before"

"$jointcomp" discover --urdf "$urdf" --params "$params" --campaign "$work/fit.csv" --holdout "$work/held.csv" \
  --base frame --types offset,harmonic,hysteresis,payload --max-steps 3 --out "$work/discover" --no-plot >/dev/null
"$python" - "$work/discover" <<'PY'
import json, sys
report = json.load(open(sys.argv[1] + "/report.json"))
first = report["steps"][0]
assert first["type"] == "offset" and first["joint_index"] == 3, first
assert report["final"]["held_out"][0]["rms_mm"] < 0.5 * report["initial"]["held_out"][0]["rms_mm"]
assert report["noise_floor"]["final_over_floor"] < 1.3, report["noise_floor"]
parameters = json.load(open(sys.argv[1] + "/parameters.json"))
offset = next(e for e in parameters["effects"] if e["type"] == "offset")
assert abs(offset["offset_rad"][2] - 1e-3) < 1e-4, offset
assert "plant" in parameters, "the drives of the nominal file are kept"
PY
cmp -s "$work/fit.csv" "$work/fit.before" || fail "discover modified its input campaign"
# The selection's settings are options of their own (read whole, range-checked by the library's rules).
"$jointcomp" discover --urdf "$urdf" --params "$params" --campaign "$work/fit.csv" --holdout "$work/held.csv" \
  --max-steps 0 --table-knots 16,32 --max-prior-weight 1 --max-ridge-weight 0.1 --transfer-significance 2 \
  --min-group-share 0.1 --angle-ranges 4 --no-pairs --holdout-same-instrument --out "$work/discover_options" \
  --no-plot >/dev/null || fail "discover refused its selection options"
"$python" - "$work/discover_options/report.json" <<'PY' || fail "report.json does not carry the selection options"
import json, sys
selection = json.load(open(sys.argv[1]))["selection"]
assert selection["table_knots"] == [16, 32] and selection["pairs"] is False, selection
assert selection["transfer_significance"] == 2 and selection["angle_ranges"] == 4, selection
assert selection["base"] == "textbook", selection
PY

"$jointcomp" calibrate --urdf "$urdf" --params "$params" --campaign "$work/fit.csv" --holdout "$work/held.csv" \
  --out "$work/calibrate" --no-plot >/dev/null
"$python" - "$work/calibrate/report.json" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
held = report["campaigns"][1]
assert held["role"].startswith("holdout") and held["after"]["rms_mm"] < 0.5 * held["before"]["rms_mm"], held
PY
# residuals.csv carries each row's residual vector, whose length is the row's error, and its joint mapping.
"$python" - "$work/calibrate/residuals.csv" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert {"dx_mm", "dy_mm", "dz_mm", "dq_joint_1_mrad", "dq_joint_6_mrad"} <= set(rows[0]), list(rows[0])
assert {r["role"] for r in rows} == {"calibration", "holdout"}
for r in rows:
    norm = math.sqrt(sum(float(r[k]) ** 2 for k in ("dx_mm", "dy_mm", "dz_mm")))
    assert abs(norm - float(r["after_mm"])) < 1e-6 * max(1.0, norm), r
PY
# Two campaigns in one calibration (--campaign given twice): one robot, each campaign in the reports.
"$jointcomp" calibrate --urdf "$urdf" --params "$params" --campaign "$work/fit.csv" --campaign "$work/held.csv" \
  --out "$work/calibrate_both" --no-plot >/dev/null
"$python" - "$work/calibrate_both" <<'PY'
import csv, json, sys
report = json.load(open(sys.argv[1] + "/report.json"))
fitted = [c for c in report["campaigns"] if c["role"] == "calibration"]
assert [c["file"].split("/")[-1] for c in fitted] == ["fit.csv", "held.csv"], fitted
assert sum(c["rows"] for c in fitted) == report["rows"]["used"] == 210, (fitted, report["rows"])
# Simulated in the base frame: one set-up, no frame fitted for either.
assert [s["campaigns"] for s in report["instrument_setups"]] == [[c["file"] for c in fitted]], report["instrument_setups"]
rows = list(csv.DictReader(open(sys.argv[1] + "/residuals.csv")))
assert {r["campaign"] for r in rows} == {"fit.csv", "held.csv"} and len(rows) == 210
summary = open(sys.argv[1] + "/summary.txt").read()
assert "2 campaigns from 1 instrument set-up" in summary and "held.csv (calibration)" in summary, summary[:600]
PY
test -s "$work/calibrate/rx170_calibrated.urdf" || fail "calibrate wrote no URDF"
# The URDF's note says what the parameter file holds of the compliance, as report.json does.
"$python" - "$work/calibrate/rx170_calibrated.urdf" "$work/calibrate/report.json" <<'PY'
import json, sys
note = open(sys.argv[1]).read()
left_out = json.load(open(sys.argv[2]))["compliance_left_out"]
if left_out:  # the joints written rigid, by name
    names = ", ".join(item.split(":")[0] for item in left_out)
    assert "it writes the compliance of %s as rigid" % names in note, note[:600]
else:
    assert "Joint offsets and compliance are in the parameter file." in note, note[:600]
assert "The chain ends at link 'flange_target'" in note or "The chain ends at link '" in note, note[:600]
PY
# Each identified parameter's value is printed in the unit its name says, then in the unit people read:
# target.z_m 0.15 m = 150 mm, not "target.z_m 150 mm".
"$python" - "$work/calibrate/summary.txt" "$work/calibrate/report.json" <<'PY'
import json
import re
import sys

summary = open(sys.argv[1]).read()
report = json.load(open(sys.argv[2]))
checked = 0
for line in summary.splitlines():
    match = re.match(r"\s+(\S+_(m|rad))\s+(\S+) \+- \S+\s+(m|rad)\s+= (\S+) \+- \S+ (mm|deg)", line)
    if not match:
        continue
    name, unit, value, shown_unit, converted, readable = match.groups()
    assert unit == shown_unit, line
    factor = 1e3 if unit == "m" else 180.0 / 3.141592653589793
    assert abs(float(converted) - float(value) * factor) <= 1e-5 * max(1.0, abs(float(converted))), line
    checked += 1
assert checked >= 3, "no parameter lines in the summary:\n" + summary
PY

# What the calibration leaves is the tracker's noise here: its neighbours in joint space must not predict
# it (examples/python/residual_neighbours.py, the analysis quoted in the README for the UR10).
if [ -n "$library" ]; then
  JOINTCOMP_LIBRARY="$library" "$python" "$(dirname "$0")/../../examples/python/residual_neighbours.py" \
    "$work/calibrate" "$work/fit.csv" --neighbours 3,10 >"$work/neighbours.txt"
  "$python" - "$work/neighbours.txt" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
rms = float(re.search(r"residual RMS ([0-9.]+) mm", text).group(1))
left = [float(x) for x in re.findall(r"nearest poses: ([0-9.]+) mm", text)]  # at any time
assert 0.005 < rms < 0.1, rms  # the simulated tracker's noise, in mm
assert len(left) == 2 and all(x > 0.95 * rms for x in left), (rms, left)
PY
fi

# Mistakes: a non-zero exit and a message naming what is wrong.
expect_error() {  # expect_error FRAGMENT ARGS...
  local fragment="$1"
  shift
  local output status=0
  output="$("$jointcomp" "$@" 2>&1)" || status=$?
  [ "$status" -ne 0 ] || fail "'jointcomp $*' succeeded"
  grep -qF -- "$fragment" <<<"$output" || fail "'jointcomp $*' said '$output', not '$fragment'"
}
expect_error "unknown protocol 'circle'" simulate --protocol circle --truth "$params" --out "$work/x.csv"
expect_error "--warm-up takes" simulate --protocol random --truth "$params" --warm-up 1,2,3,4 --out "$work/x.csv"
expect_error "--warm-up: '0' is out of range: it must be greater than 0" simulate --protocol random --truth "$params" --warm-up 5,0 --out "$work/x.csv"
expect_error "missing.csv" discover --campaign "$work/missing.csv" --out "$work/x"
expect_error "unknown effect type 'gremlin'" discover --campaign "$work/fit.csv" --types gremlin --out "$work/x"
# A malformed "plant" object is an error in every command that reads the file, not only in those that
# simulate (the parameter set is read once, whole).
"$python" - "$params" "$work/bad_plant.json" <<'PY'
import json, sys
document = json.load(open(sys.argv[1]))
document["plant"]["joints"][1]["kp_nm_per_rad"] = -5
json.dump(document, open(sys.argv[2], "w"), indent=2)
PY
for command in calibrate discover; do
  expect_error "kp_nm_per_rad" $command --urdf "$urdf" --params "$work/bad_plant.json" --campaign "$work/fit.csv" --out "$work/x"
done
expect_error "kp_nm_per_rad" identify stiffness --params "$work/bad_plant.json" --campaign "$work/fit.csv" --out "$work/x"
expect_error "kp_nm_per_rad" paper --quasi-static --params "$work/bad_plant.json" --out "$work/x"
expect_error "--feed-rate: '3' is out of range: it must be from 0.003 to 2" paper --quasi-static --feed-rate 3 --out "$work/x"
expect_error "--feed-rate: 'fast' is not a number" paper --quasi-static --feed-rate fast --out "$work/x"
expect_error "identify: unknown kind 'speed'" identify speed --campaign "$work/fit.csv" --out "$work/x"
# A user's own export (';', decimal commas, a title line, its own names, radians and metres) imported, and the
# campaign it gives read by calibrate's reader (a mapping to a missing column is refused naming the header).
printf 'Export of 2026-11-25\nTime;A1;A2;A3;A4;A5;A6;X;Y;Z\n0;0,1;0,2;0,3;0;0,5;0;1,2;0,1;0,9\n1;0,2;0,3;0,4;0;0,5;0;1,1;0,2;0,8\n' \
  >"$work/export.csv"
"$jointcomp" import-csv --in "$work/export.csv" --out "$work/imported.csv" --angles rad --lengths m \
  --columns t=Time,q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,q6=A6 >/dev/null || fail "import-csv failed"
head -n 1 "$work/imported.csv" | grep -c "^# format: jointcomp-measurements/1" >/dev/null || fail "import-csv wrote no campaign"
grep -q "^1,11.459155902616" "$work/imported.csv" || fail "import-csv did not convert radians to degrees"
expect_error "column 'Zeit' (mapped to t) is not in the header" import-csv --in "$work/export.csv" \
  --out "$work/x.csv" --columns t=Zeit
# A command line that explains itself: every command's --help lists its options (exit 0), an unknown option
# is a usage error (exit 2) that shows the command's usage, --version says the version.
for command in paper kinematics import-ipa import-csv simulate "identify stiffness" calibrate discover; do
  # shellcheck disable=SC2086  # "identify stiffness" is two words
  help="$("$jointcomp" $command --help)" || fail "jointcomp $command --help failed"
  grep -q "^Usage: jointcomp $command \[OPTIONS\]" <<<"$help" || fail "jointcomp $command --help shows no usage"
  grep -q -- "--out" <<<"$help" || [ "$command" = kinematics ] || fail "jointcomp $command --help lists no --out"
  status=0
  # shellcheck disable=SC2086
  output="$("$jointcomp" $command --bogus 2>&1)" || status=$?
  [ "$status" -eq 2 ] || fail "jointcomp $command --bogus exited $status, not 2"
  grep -q "Usage: jointcomp $command" <<<"$output" || fail "jointcomp $command --bogus shows no usage"
done
"$jointcomp" --version | grep -c "^jointcomp [0-9]*\.[0-9]*\.[0-9]*$" >/dev/null || fail "jointcomp --version"

# The chain of a URDF in the ROS-Industrial layout: tool0 by default, another tip on request; a tree
# with two tools of the same chain is refused naming where it branches.
ros_urdf="$(dirname "$0")/../data/urdf/ur10_ros_industrial.urdf"
"$jointcomp" kinematics --urdf "$ros_urdf" | grep -c "tool link 'tool0'" >/dev/null || fail "the ROS-Industrial tip is not tool0"
"$jointcomp" kinematics --urdf "$ros_urdf" --tip-link flange | grep -c "tool link 'flange'" >/dev/null ||
  fail "--tip-link flange was not taken"
expect_error "branches at link 'link_3'" kinematics --urdf "$(dirname "$0")/../data/urdf/two_tools.urdf"
test ! -e "$work/x.csv" || fail "a refused simulate wrote its output"
echo "cli_workflow: every step gave what the truth says"
