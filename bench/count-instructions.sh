#!/usr/bin/env bash
# Counts the instructions of the hot paths with valgrind's callgrind: per FMU communication step (1 ms and
# 10 ms, FMI 2 and 3, the FMU's defaults), the same step on the plant and compensator called directly (the
# difference is the FMI layer's own cost), per compensated point, and one plant right-hand side against
# forward dynamics, ours and KDL's; a Monte Carlo draw of the spiral against its three compensations. Counts
# do not move with the machine's load or clock, which the timings
# of run-benchmarks.sh and fmu_bench do (on a shared machine by up to half); an instruction is not a cycle,
# so a count compares builds and code paths, and a timing says how fast.
# Each FMU figure is the mean over one whole spiral (fmu_bench --whole_spirals=1), so that two builds count
# the same work. About a minute on one core.
#   bench/count-instructions.sh [BUILD_DIR]   (default build/bench; a folder without a CMake cache is
#   configured here in Release, an existing one is only built, with its own settings)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="${1:-build/bench}"
python=/usr/bin/python3  # Debian's interpreter: the python3 first on PATH may be another one
for tool in valgrind callgrind_annotate; do
  if ! command -v "$tool" >/dev/null; then
    echo "count-instructions: $tool is missing (apt install valgrind)" >&2
    exit 1
  fi
done

if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DJOINTCOMP_BUILD_TESTS=OFF >/dev/null
fi
cmake --build "$build_dir" --target fmu_bench compensation_bench plant_bench montecarlo_bench -j"$(nproc)" >/dev/null

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# callgrind over one benchmark run; the annotated call tree goes to $work/NAME.tree.
profile() {
  local name="$1"
  shift
  echo "counting $name ..." >&2
  valgrind --tool=callgrind --callgrind-out-file="$work/$name.out" "$@" >/dev/null 2>"$work/$name.log" || {
    echo "count-instructions: the run for $name failed; its log:" >&2
    cat "$work/$name.log" >&2
    exit 1
  }
  callgrind_annotate --tree=calling --threshold=100 "$work/$name.out" >"$work/$name.tree" 2>/dev/null
}

fmu="$build_dir/bench/fmu_bench"
for step_ms in 1 10; do
  for fmi in 2 3; do
    profile "fmu${fmi}_${step_ms}ms" "$fmu" --whole_spirals=1 \
      --benchmark_filter="^BM_FmuSpiral/fmi:$fmi/all_outputs:0/step_ms:$step_ms/past_ms:10/"
  done
  profile "direct_${step_ms}ms" "$fmu" --whole_spirals=1 \
    --benchmark_filter="^BM_DirectSpiral/smooth:0/step_ms:$step_ms/past_ms:10/"
done
profile compensation "$build_dir/bench/compensation_bench" --benchmark_min_time=0.2 \
  --benchmark_filter='^BM_Ours_CompensateSpiral(Point|Path)$'
profile montecarlo "$build_dir/bench/montecarlo_bench" --benchmark_min_time=0.1 \
  --benchmark_filter='^BM_(Draw|ThreeCompensations)$'
profile dynamics "$build_dir/bench/plant_bench" --benchmark_min_time=0.1 \
  --benchmark_filter='^BM_(Ours_PlantRightHandSide|Ours_ForwardDynamics|Kdl_ForwardDynamics)$'

"$python" - "$work" <<'EOF'
import re
import sys

work = sys.argv[1]
# A callee line of callgrind_annotate's calling tree: inclusive cost, ">", the function, its call count.
callee = re.compile(r"^\s*([\d,]+)\s+(?:\(\s*[\d.]+%\)\s+)?>\s+(.*?)\s+\(([\d,]+)x\)")

def per_call(name, function):
    """Mean inclusive instructions per call of `function` (a substring of its name) in run `name`."""
    cost = calls = 0
    with open(f"{work}/{name}.tree") as tree:
        for line in tree:
            match = callee.match(line)
            if match and function in match.group(2):
                cost += int(match.group(1).replace(",", ""))
                calls += int(match.group(3).replace(",", ""))
    if calls == 0:
        sys.exit(f"count-instructions: no call of {function} in the {name} run")
    return cost / calls, calls

print("Instructions per call (callgrind; the same on every machine, unlike a timing)")
for step_ms in (1, 10):
    direct, steps = per_call(f"direct_{step_ms}ms", "directStep(")
    print(f"\nRX170 spiral, {step_ms} ms communication step, CVODE stepping past communication points (the "
          f"FMU's default), {steps} steps")
    print(f"  {'plant + compensator called directly':52s} {direct:9,.0f}")
    for fmi in (2, 3):
        step, _ = per_call(f"fmu{fmi}_{step_ms}ms", "fmuStep(")
        layer = step - direct
        print(f"  {f'FMU, FMI {fmi} (set 6 inputs, doStep, get 9 outputs)':52s} {step:9,.0f}"
              f"   FMI layer {layer:+,.0f} ({100 * layer / step:.1f} % of the step)")

lone, _ = per_call("compensation", "Compensator::compensate(")
path, _ = per_call("compensation", "Compensator::compensateFrom(")
print("\nCompensation of the spiral's points (stiffness, balancer, transmission error)")
print(f"  {'a lone point (compensate)':52s} {lone:9,.0f}")
print(f"  {'along the path (compensateFrom)':52s} {path:9,.0f}")

draw, _ = per_call("montecarlo", "jointcomp::drawSpiralRuns(")
compensation, _ = per_call("montecarlo", "jointcomp::compensateTrajectory(")
print("\nA quasi-static Monte Carlo draw of the spiral (three runs settled and measured) against the spiral's "
      "three compensations (issue 44's target: at most 3 times)")
print(f"  {'a draw (drawSpiralRuns)':52s} {draw:9,.0f}")
print(f"  {'three compensations (compensateTrajectory)':52s} {3 * compensation:9,.0f}   ratio {draw / (3 * compensation):.2f}")

rhs, _ = per_call("dynamics", "FlexibleJointPlant::derivative(")
ours, _ = per_call("dynamics", "jointcomp::forwardDynamics(jointcomp::Robot const&")
kdl, _ = per_call("dynamics", "KDL::ChainFdSolver_RNE::CartToJnt(")
print("\nDynamics of the RX170")
print(f"  {'one plant right-hand side':52s} {rhs:9,.0f}")
print(f"  {'forward dynamics, ours':52s} {ours:9,.0f}")
print(f"  {'forward dynamics, KDL (ChainFdSolver_RNE)':52s} {kdl:9,.0f}")
print(f"  right-hand side / KDL's forward dynamics: {rhs / kdl:.2f}; our forward dynamics / KDL's: {ours / kdl:.2f}")
EOF
