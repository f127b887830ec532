#!/usr/bin/env bash
# Installs every build, test, benchmark and example dependency of jointcomp from Debian's packages.
# Idempotent: apt-get skips what is already there. Run as root (or with sudo available).
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libeigen3-dev            # linear algebra of the whole model
  libsundials-dev          # CVODE integrates the flexible-joint plant (static libs ship with it: FMU)
  liburdfdom-dev           # the robot description is URDF
  nlohmann-json3-dev       # parameter files and reports: header-only, well kept, in Debian
  libcli11-dev             # the command line: --help for every command, usage on errors
  libgtest-dev libgmock-dev googletest  # unit tests
  libbenchmark-dev         # Google Benchmark: speed targets live in benchmarks, not tests
  liborocos-kdl-dev libkdl-parser-dev   # KDL: the peer our kinematics and dynamics are measured against
  libxml2-utils            # xmllint validates modelDescription.xml against the FMI schemas
  python3-numpy python3-matplotlib python3-pytest python3-pycparser  # bindings, plots, binding tests
  python3-venv python3-pip python3-setuptools python3-wheel  # the pip install of the bindings (tests/packaging)
  python3-distributed python3-dask  # jointcomp.distributed: Monte Carlo and fleet calibration on a Dask cluster
  dpkg-dev                 # dpkg-shlibdeps: the .deb's dependencies (cpack, tests/packaging)
  zip unzip                # packs and unpacks the FMU
  clang libclang-rt-14-dev # sanitizers and libFuzzer
  valgrind                 # memcheck of the FMU importer test (test.sh, tests/load/run-load.sh)
  clang-format clang-tidy  # packaging/format.sh and packaging/tidy.sh keep the style and the checks
  doxygen                  # the C API's reference (docs/build-reference.sh, CTest docs_reference)
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
