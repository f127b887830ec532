#!/usr/bin/env bash
# Builds the benchmarks (Release, build/bench) and compares jointcomp's robot algorithms with KDL on the
# RX170: per call, the median over 3 repetitions of the CPU time, ours / KDL, and the allocations per call.
# Then the flexible-joint plant (plant_bench): the real-time factor of the paper's spiral and the cost of
# one right-hand side next to forward dynamics, ours and KDL's.
# Run from anywhere; arguments are passed on to robot_bench (e.g. --benchmark_filter=Gravity), not to
# plant_bench, which always runs whole.
#   bench/run-benchmarks.sh
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="build/bench"
json="$build_dir/robot_bench.json"
python=/usr/bin/python3  # Debian's interpreter: the python3 first on PATH may be another one

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DJOINTCOMP_BUILD_TESTS=OFF >/dev/null
cmake --build "$build_dir" --target robot_bench plant_bench compensation_bench -j"$(nproc)"

# The binary cross-checks ours against KDL before timing anything (exit 2 if they disagree) and fails
# (exit 3) if one of our calls allocated in its timed loop.
echo "running robot_bench (3 repetitions of each benchmark, medians; about half a minute) ..." >&2
status=0
# 0.25 s per repetition keeps the whole run near 30 s on 2 cores; later arguments override these.
"$build_dir/bench/robot_bench" --benchmark_format=json --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_min_time=0.25 "$@" >"$json" || status=$?
if [ "$status" -ne 0 ]; then
  echo "robot_bench failed (exit $status); see the message above. JSON so far: $json" >&2
  exit "$status"
fi

"$python" - "$json" <<'EOF'
import json
import sys

with open(sys.argv[1]) as f:
    report = json.load(f)

scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
median = {}  # run name -> (cpu ns per call, allocs per call)
for b in report["benchmarks"]:
    if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
        continue
    name = b.get("run_name", b["name"])
    median[name] = (b["cpu_time"] * scale[b.get("time_unit", "ns")], b.get("allocs_per_call", float("nan")))

calls = [
    ("ForwardKinematics", "forward kinematics"),
    ("ToolPosition", "tool position alone (no other pose)"),
    ("Jacobian", "Jacobian (with its FK)"),
    ("Gravity", "gravity torques"),
    ("GravityInJointFrames", "gravity torques in joint frames (no FK)"),
    ("FkJacobianGravity", "FK+Jacobian+gravity"),
    ("InverseDynamics", "RNEA (inverse dynamics)"),
    ("MassMatrix", "mass matrix"),
    ("ForwardDynamics", "forward dynamics"),
]
targets = {"FkJacobianGravity": 0.5, "ForwardDynamics": 0.5}

peer = {"GravityInJointFrames": "Gravity", "ToolPosition": "ForwardKinematics"}  # ours done another way, against KDL's same call

def kdl_fastest(call):
    """KDL's fastest way to do the call: BM_Kdl_<call> or one of its variants BM_Kdl_<call>_<variant>."""
    call = peer.get(call, call)
    candidates = [(t, a, n) for n, (t, a) in median.items()
                  if n == "BM_Kdl_" + call or n.startswith("BM_Kdl_" + call + "_")]
    return min(candidates) if candidates else None

rows = []
ratios = {}
for call, label in calls:
    ours = median.get("BM_Ours_" + call)
    kdl = kdl_fastest(call)
    if ours is None or kdl is None:
        continue
    ratio = ours[0] / kdl[0]
    ratios[call] = ratio
    variant = kdl[2][len("BM_Kdl_" + peer.get(call, call)):].lstrip("_")
    rows.append((label, f"{ours[0]:.0f}", f"{kdl[0]:.0f}" + (f" ({variant})" if variant else ""),
                 f"{ratio:.3f}", f"{ours[1]:g} / {kdl[1]:g}"))

header = ("call", "ours ns", "KDL ns", "ours/KDL", "allocs per call (ours / KDL)")
widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
line = lambda r: "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
print()
print("RX170, median of 3 repetitions, CPU time per call; 64 seeded configurations cycled")
print(line(header))
print(line(tuple("-" * w for w in widths)))
for r in rows:
    print(line(r))
print()
for call, label in calls:
    alternatives = sorted((n, t) for n, (t, _) in median.items() if n.startswith("BM_Kdl_" + call + "_"))
    if len(alternatives) > 1:
        print(f"KDL {label}: fastest variant taken; " +
              ", ".join(f"{n[len('BM_Kdl_' + call) + 1:]} {t:.0f} ns" for n, t in alternatives))
print("target: FK+Jacobian+gravity and forward dynamics at most 0.5 of KDL")
for call, limit in targets.items():
    if call in ratios:
        verdict = "met" if ratios[call] <= limit else "NOT met"
        label = dict(calls)[call]
        print(f"  {label}: {ratios[call]:.3f} of KDL -> {verdict}")
EOF

# The plant: BM_Ours_PlantSpiral runs the whole experiment 3 times per repetition (a few seconds in all).
plant_json="$build_dir/plant_bench.json"
echo "running plant_bench (3 repetitions, medians; about ten seconds) ..." >&2
status=0
"$build_dir/bench/plant_bench" --benchmark_format=json --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_min_time=0.25 >"$plant_json" || status=$?
if [ "$status" -ne 0 ]; then
  echo "plant_bench failed (exit $status); see the message above. JSON so far: $plant_json" >&2
  exit "$status"
fi

"$python" - "$plant_json" <<'EOF'
import json
import sys

with open(sys.argv[1]) as f:
    report = json.load(f)

scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
median = {}  # benchmark name (without /iterations:.. suffixes) -> its median aggregate
for b in report["benchmarks"]:
    if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
        continue
    median[b.get("run_name", b["name"]).split("/")[0]] = b

def ns(name):
    b = median[name]
    return b["cpu_time"] * scale[b.get("time_unit", "ns")]

print()
spiral = median.get("BM_Ours_PlantSpiral")
if spiral:
    print("Plant: the paper's spiral on the flexible-joint RX170 (default tolerances), median of 3 repetitions")
    print(f"  {spiral['real_time_factor']:.0f}x real time ({spiral['simulating_s']:.3f} s simulating "
          f"{spiral['motion_s']:.1f} s of motion, 3 runs); per experiment CVODE took {spiral['steps']:.0f} steps, "
          f"{spiral['rhs_evaluations']:.0f} right-hand sides, {spiral['jacobian_evaluations']:.0f} Jacobians")
rows = []
for name, label in (("BM_Ours_PlantRightHandSide", "plant right-hand side (ours)"),
                    ("BM_Ours_ForwardDynamics", "forward dynamics (ours)"),
                    ("BM_Kdl_ForwardDynamics", "forward dynamics (KDL)")):
    if name in median:
        rows.append((label, f"{ns(name):.0f}", f"{median[name].get('allocs_per_call', float('nan')):g}"))
if rows:
    header = ("call", "CPU ns", "allocs per call")
    widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
    line = lambda r: "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
    print(line(header))
    print(line(tuple("-" * w for w in widths)))
    for r in rows:
        print(line(r))
    if "BM_Ours_PlantRightHandSide" in median and "BM_Kdl_ForwardDynamics" in median:
        print(f"one plant right-hand side costs {ns('BM_Ours_PlantRightHandSide') / ns('BM_Kdl_ForwardDynamics'):.2f} "
              "of KDL's forward dynamics alone")
EOF

# Compensation throughput: spiral points per second per core, ours against the same computation with
# KDL's gravity solver.
compensation_json="$build_dir/compensation_bench.json"
echo "running compensation_bench (3 repetitions, medians; a few seconds) ..." >&2
"$build_dir/bench/compensation_bench" --benchmark_format=json --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_min_time=0.25 >"$compensation_json"
"$python" - "$compensation_json" <<'EOF'
import json, sys
runs = {b["run_name"]: b for b in json.load(open(sys.argv[1]))["benchmarks"] if b.get("aggregate_name") == "median"}
ours = runs["BM_Ours_CompensateSpiralPoint"]
kdl = runs["BM_Kdl_CompensateSpiralPoint"]
print()
print("Compensation of the spiral, all effects, iterated to 1e-12 rad (median of 3, CPU time)")
print(f"  ours: {ours['items_per_second'] / 1e6:.2f} million points/s per core "
      f"({ours['fixed_point_iterations']:.2f} fixed-point iterations per point)")
path = runs.get("BM_Ours_CompensateSpiralPath")
if path:
    print(f"  ours along the path, each point from the previous correction: {path['items_per_second'] / 1e6:.2f} "
          f"million points/s per core ({path['fixed_point_iterations']:.2f} iterations per point)")
print(f"  with KDL's gravity: {kdl['items_per_second'] / 1e6:.2f} million points/s per core")
print(f"  ours / KDL-based throughput: {ours['items_per_second'] / kdl['items_per_second']:.2f}")
print("target: at least 1 million points/s per core and at least 2x the KDL-based equivalent")
for speed in (1, 10):
    dynamic = runs.get(f"BM_Ours_DynamicCompensationSpiral/{speed}")
    if dynamic:
        print(f"dynamic compensation of the spiral at {speed}x the paper's feed rate: "
              f"{dynamic['cpu_time'] / 1e3:.2f} s CPU for {dynamic['motion_s']:.1f} s of motion "
              f"({dynamic['plant_runs']:.0f} runs of the nominal plant)")
print("target: the dynamic compensation of the 30 s spiral in under 1 s on one core")
EOF
