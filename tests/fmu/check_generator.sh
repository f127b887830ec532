#!/usr/bin/env bash
# modelDescription/generate.py refuses inconsistent tables with a message naming the row, and writes
# nothing for them. Each case corrupts a copy of the real tables in one way.
#   check_generator.sh <modelDescription folder> <parameter-values.json>
set -uo pipefail
tables="$1" values="$2"
python=/usr/bin/python3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0

expect_failure() {  # <what> <pattern in the message> <sed expression on variables.csv>
  rm -rf "$work/t" "$work/out" && cp -r "$tables" "$work/t"
  sed -i "$3" "$work/t/variables.csv"
  if message=$("$python" "$work/t/generate.py" --tables "$work/t" --values "$values" --version 0 --out-dir "$work/out" 2>&1); then
    echo "FAIL: $1: accepted"; status=1
  elif ! grep -q -- "$2" <<<"$message"; then
    echo "FAIL: $1: message '$message' lacks '$2'"; status=1
  elif [ -e "$work/out/fmi2/modelDescription.xml" ]; then
    echo "FAIL: $1: wrote output"; status=1
  else
    echo "ok: $1: $message"
  fi
}

# The real tables pass.
"$python" "$tables/generate.py" --tables "$tables" --values "$values" --version 0 --out-dir "$work/good" || status=1
expect_failure "duplicate value reference" "is already used" 's/^101,q_desired_2,/100,q_desired_2,/'
expect_failure "duplicate name" "is already used" 's/^101,q_desired_2,/101,q_desired_1,/'
expect_failure "unknown unit" "not in units.csv" 's/^100,q_desired_1,input,continuous,,Real,rad,/100,q_desired_1,input,continuous,,Real,furlong,/'
expect_failure "input without start" "need a start value" 's/^100,q_desired_1,input,continuous,,Real,rad,0,/100,q_desired_1,input,continuous,,Real,rad,,/'
expect_failure "output with start" "have no start value" 's/^220,q_link_1,output,continuous,,Real,rad,,/220,q_link_1,output,continuous,,Real,rad,1,/'
expect_failure "unknown model parameter" "is not among the effects parameters" 's/plant:joint_1.stiffness_nm_per_rad/plant:joint_1.stiffnes/'
expect_failure "bound parameter with a start" "leave start empty" 's/^1000,plant.joint_1.stiffness,parameter,fixed,,Real,N.m\/rad,,/1000,plant.joint_1.stiffness,parameter,fixed,,Real,N.m\/rad,5,/'
expect_failure "not a structured name" "not a structured name" 's/^100,q_desired_1,/100,q desired 1,/'
expect_failure "continuous Boolean" "only Real variables can be continuous" 's/^2,use_velocity_inputs,parameter,fixed,/2,use_velocity_inputs,parameter,continuous,/'
expect_failure "missing role index" "expected 0..n-1" '/^101,q_desired_2,/d'
exit $status
