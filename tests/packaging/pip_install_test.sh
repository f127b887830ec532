#!/usr/bin/env bash
# The Python package installs with pip, offline, into a virtual environment made with
# --system-site-packages (Debian's numpy and setuptools), and works from there.
# usage: pip_install_test.sh <source dir> <libjointcomp.so> <project version> <work dir>
set -euo pipefail
source="$1" library="$2" version="$3" work="$4"
rm -rf "$work"
mkdir -p "$work"
# pip builds in the folder it is given: a copy keeps build/ and *.egg-info out of the source tree.
cp -r "$source/capi/python" "$work/package"
rm -rf "$work/package/jointcomp/__pycache__"

echo "== the package's version is the project's"
declared=$(sed -n 's/^version = "\(.*\)"$/\1/p' "$work/package/pyproject.toml")
[ "$declared" = "$version" ] || { echo "pyproject.toml says $declared, CMakeLists.txt $version"; exit 1; }

echo "== pip install into a virtual environment"
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --no-index --no-build-isolation --no-cache-dir \
  --disable-pip-version-check "$work/package"
shown=$("$work/venv/bin/python" -m pip show jointcomp)
echo "$shown" | grep "^Version: $version$"

echo "== without a library it says how to give one"
if message=$(cd "$work" && env -u JOINTCOMP_LIBRARY -u LD_LIBRARY_PATH "$work/venv/bin/python" -c 'import jointcomp' 2>&1); then
  # Only when a libjointcomp is installed system-wide (ldconfig) may this succeed.
  echo "$message"
  ldconfig -p | grep -c libjointcomp >/dev/null || { echo "imported without any library to load"; exit 1; }
else
  echo "$message" | grep -c "set JOINTCOMP_LIBRARY" >/dev/null || { echo "unclear failure: $message"; exit 1; }
fi

echo "== with JOINTCOMP_LIBRARY it loads, has __version__ and computes a batch"
cd "$work"  # not the source tree: the import must come from the environment
JOINTCOMP_LIBRARY="$library" PYTHONDONTWRITEBYTECODE=1 "$work/venv/bin/python" - "$source" "$version" "$work/venv" <<'PY'
import pathlib
import sys

import numpy as np

import jointcomp

source, version, venv = sys.argv[1:]
assert pathlib.Path(jointcomp.__file__).resolve().is_relative_to(pathlib.Path(venv).resolve()), jointcomp.__file__
assert jointcomp.__version__ == version, (jointcomp.__version__, version)
with jointcomp.Robot(source + "/model/robots/rx170.urdf", source + "/model/params/rx170.json") as robot:
    poses = np.array([[0.0, -0.3, 1.9, 0.0, 0.4, 0.0], [0.2, -0.1, 1.5, 0.3, -0.2, 0.1]])
    batch = robot.forward_kinematics(poses)
    for pose, transform in zip(poses, batch):
        assert np.array_equal(robot.forward_kinematics(pose), transform)
print("jointcomp", jointcomp.__version__, "from", jointcomp.__file__)
PY
