#!/usr/bin/env bash
# The measurements of docs/ur10-study.md on the real UR10 (what the textbook calibration leaves), made again from the data by
# examples/python/ur10_residual_study.py after jointcomp's own import and calibration:
# B's poses lie far from A's, A's residual field makes B worse, no output harmonic fitted on A helps B much,
# the T-Mac's orientation residual is repeatable but not explained by a full kinematic orientation model, and
# the residual lies across the tracker's beam without being a function of the direction from the tracker.
#   ur10_study.sh <jointcomp> <scratch folder>        (needs JOINTCOMP_SHARED; exits 77, a skip, without it)
set -euo pipefail
jointcomp="$1" work="$2"
source "$(dirname "$0")/../support/shared_data.sh"
require_shared_file raw_b "the IPA UR10 data" data/ipa-ur10/Series_B/measurements_joint_configurations.csv
data="$JOINTCOMP_SHARED/data/ipa-ur10"
python=/usr/bin/python3
rm -rf "$work" && mkdir -p "$work"
"$jointcomp" import-ipa --in "$data/Series_A/measurements_grid.csv" --trafo "$data/Series_A/Trafo_TM_F_init.txt" \
  --out "$work/A.csv" >/dev/null
"$jointcomp" import-ipa --in "$raw_b" \
  --trafo "$data/Series_B/Trafo_TM_F_init.txt" --out "$work/B.csv" >/dev/null
model="$(dirname "$0")/../../model/robots/ur10.urdf"
"$jointcomp" calibrate --urdf "$model" --campaign "$work/A.csv" --holdout "$work/B.csv" --out "$work/calibrate" \
  --no-plot >/dev/null
"$python" "$(dirname "$0")/../../examples/python/ur10_residual_study.py" "$work/calibrate" "$work/A.csv" "$work/B.csv" \
  --max-order 30 --raw-b "$raw_b" --trafo-b "$data/Series_B/Trafo_TM_F_init.txt" \
  --raw-a "$data/Series_A/measurements_grid.csv" --trafo-a "$data/Series_A/Trafo_TM_F_init.txt" >"$work/study.txt"
cat "$work/study.txt"
"$python" - "$work/study.txt" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
number = lambda pattern: float(re.search(pattern, text).group(1))
distance = number(r"lie ([0-9.]+) rad \(median\)")
b_rms = number(r"B's RMS ([0-9.]+) mm")
b_after = number(r"frame re-fitted\): ([0-9.]+) mm")
best_b = number(r"best on B of all: ([-+0-9.]+) %")
first = [float(x) for x in re.findall(r"first session ([-+0-9. ]+) %", text)]
after_frames = number(r"([0-9.]+) mrad after every small rotation")
repeat = number(r"agree to ([0-9.]+) mrad")
along_a = number(r"4\. A: along the line of sight ([0-9.]+) mm")
across_a = number(r"4\. A: .* across it ([0-9.]+) mm")
tracker_share = number(r"fitted on A: .* mm, ([-0-9.]+) % of its squares")
assert distance > 1.0, distance            # B reaches its goals in other configurations than A
assert b_after > b_rms, (b_after, b_rms)   # A's residual field does not carry to B
assert max(first) > 20.0, first            # a harmonic fits A's first session...
assert best_b < 15.0, best_b               # ...but none helps B much
assert after_frames > 5.0 * repeat, (after_frames, repeat)  # repeatable, and not kinematic
assert across_a > 1.5 * along_a, (across_a, along_a)  # A's residual lies across the beam: angles...
assert tracker_share < 10.0, tracker_share             # ...but not the tracker's: no function of its direction
runout = [tuple(map(float, m)) for m in re.findall(r"bearing runout of .*: A ([0-9.]+) -> ([0-9.]+) mm, B ([0-9.]+) -> ([0-9.]+) mm", text)]
assert len(runout) == 7, runout
assert all(b_after > 0.95 * b_before for _, _, b_before, b_after in runout), runout  # no bearing's tilt carries to B
thermal = re.search(r"thermal expansion .*: A ([0-9.]+) -> ([0-9.]+) mm", text).groups()
assert float(thermal[1]) > 0.99 * float(thermal[0]), thermal  # nor the links' expansion with the air temperature
pair = re.search(r"they share ([0-9.]+) % of the residual's squares, where a constant angle error of joint 2, 3 or 4 "
                 r"would share ([0-9.]+), ([0-9.]+) and ([0-9.]+) %", text)
shared, joint_2, joint_3, joint_4 = map(float, pair.groups())
assert shared > 50.0, shared                        # most of B's residual is common to a goal's elbow configurations
assert joint_2 > 99.0 and joint_4 > 99.0, pair.groups()  # as constant errors of joints 2 and 4 would be...
assert joint_3 < shared - 20.0, pair.groups()       # ...and unlike joint 3's, which the elbow changes
fields = re.search(r"\(degree 4, [0-9]+ parameters\) leaves ([0-9.]+) mm and harmonics of joint 1 .* parameters\) "
                   r"([0-9.]+) mm of B's ([0-9.]+) mm", text)
position_field, joint_1, b_total = map(float, fields.groups())
assert position_field > 0.8 * b_total and joint_1 > 0.8 * b_total, fields.groups()  # neither explains B, even on B
coupling = re.search(r"it takes A from ([0-9.]+) to ([0-9.]+) mm and, with B's measured orientations, B from ([0-9.]+) "
                     r"to ([0-9.]+) mm", text)
a_before, a_coupled, b_before, b_coupled = map(float, coupling.groups())
assert a_coupled < 0.85 * a_before, coupling.groups()  # the position residual goes with the T-Mac's orientation residual
assert b_coupled < 0.90 * b_before, coupling.groups()  # and the coupling fitted on A carries to B
print("the UR10 study holds")
PY
