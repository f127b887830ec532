#!/usr/bin/env bash
# `jointcomp paper` runs the paper's whole method (issue 43): it measures and identifies the simulated robot,
# then compensates with the identified model. Checked here: the identified model's runs, the floor and the
# identification are in summary.json and the table; the C API / Python call on the same truth and seed gives
# the same numbers as the command (jc_identify_and_compensate against summary.json); the report it writes is
# one `jointcomp montecarlo --report` takes (its law drawn, serially); --nominal-only keeps the old run.
# usage: paper_identification.sh JOINTCOMP_BINARY LIBRARY SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
library="$2"
work="$3"
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
fail() { echo "paper_identification: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cd "$work"

"$jointcomp" paper --quasi-static --no-dynamic-correction --seed 7 --no-plot --out p >log.txt 2>&1 ||
  { cat log.txt; fail "paper failed"; }
grep -q "^stiffness and kinematic correction *identified model" log.txt || { cat log.txt; fail "no identified row"; }
grep -q "^stiffness and kinematic correction *perfect model (floor)" log.txt || fail "no floor row"
grep -q "Joint stiffness identified" log.txt || fail "the identified stiffnesses were not printed"
for f in params.json truth.json report.json stiffness_report.json transmission_report.json summary.txt \
  stiffness_campaign.csv sweep_campaign.csv; do
  [ -s "p/identification/$f" ] || fail "no identification/$f"
done

JOINTCOMP_LIBRARY="$library" PYTHONPATH="$source_dir/capi/python" PYTHONDONTWRITEBYTECODE=1 \
  /usr/bin/python3 - "$source_dir" p <<'PY'
import json
import pathlib
import sys

import jointcomp
from jointcomp import distributed

source, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
summary = json.loads((out / "summary.json").read_text())
runs = {r["name"]: r for r in summary["identified_model_runs"]}
assert [r["name"] for r in summary["perfect_model_runs"]] == ["stiffness and kinematic correction"], summary
assert summary["identification"]["stiffness"][1]["joint"] == "joint_2"
urdf = source / "model" / "robots" / "rx170.urdf"
with jointcomp.Robot(urdf, source / "model" / "params" / "rx170.json") as nominal, \
        jointcomp.Robot(urdf, out / "identification" / "truth.json") as truth:
    identified, metrics, report = jointcomp.identify_and_compensate(nominal, truth, seed=7)
    with identified:
        # The C API's runs are the command's, to the JSON's 17 digits (the truth went through a file).
        for index, name in ((1, "stiffness correction"), (2, "stiffness and kinematic correction")):
            for key, got in (("ra_mm", metrics[index].ra * 1e3), ("rz_mm", metrics[index].rz * 1e3)):
                want = runs[name][key]
                assert abs(got - want) <= 1e-9 * abs(want), (name, key, got, want)
        assert report.data["format"] == "jointcomp-identification-reports/1"
        assert metrics[2].ra < 0.5 * metrics[0].ra
# The report gives Monte Carlo a law: the identified stiffnesses, joint 2's harmonics and the refitted balancer,
# with their errors (bound to the robot's parameters by the run below, which names any it does not know).
entries, left = distributed.report_distribution(out / "identification" / "report.json")
names = [e["parameter"] for e in entries]
assert "joint_2.stiffness_nm_per_rad" in names and any(n.startswith("joint_2.harmonic_stage_2_x2") for n in names), names
assert "joint_2.spring_balancer.stiffness_n_per_m" in names, names
distributed.monte_carlo(str(urdf), str(out / "identification" / "params.json"), samples=2, seed=1,
                        report=str(out / "identification" / "report.json"), serial=True)
print("paper_identification: C API = CLI; Monte Carlo takes the report (%d laws)" % len(entries))
PY

"$jointcomp" paper --quasi-static --no-dynamic-correction --nominal-only --no-plot --out n >log2.txt 2>&1 ||
  { cat log2.txt; fail "paper --nominal-only failed"; }
[ ! -e n/identification ] || fail "--nominal-only identified"
! grep -q "identified model" log2.txt || fail "--nominal-only printed identified rows"
/usr/bin/python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); assert "identified_model_runs" not in s and len(s["runs"]) == 3' \
  n/summary.json || fail "--nominal-only summary.json"
# A parameter file the campaigns cannot identify (no compliance): the reason, and the way round it.
echo '{"format": "jointcomp-parameters/1", "robot": "rx170", "effects": []}' >minimal.json
if "$jointcomp" paper --quasi-static --params minimal.json --no-plot --out m >log3.txt 2>&1; then
  fail "paper identified a robot without compliance"
fi
grep -q "no compliance effect.*--nominal-only" log3.txt || { cat log3.txt; fail "no reason or way round it"; }
echo "paper_identification: passed"
