#!/usr/bin/env bash
# CPack's .deb holds the library, its header, the command-line tool with its data and plot scripts, the
# FMUs and the Python package; unpacked into a temporary root (no dpkg -i: the test must not change the
# machine), the tool runs the main job and plots from there, and the Python package loads the library
# from there.
# usage: deb_package_test.sh <build dir> <project version> <work dir>
set -euo pipefail
build="$1" version="$2" work="$3"
rm -rf "$work"
mkdir -p "$work/root" "$work/run"
cpack --config "$build/CPackConfig.cmake" -B "$work" >"$work/cpack.log" 2>&1 || { cat "$work/cpack.log"; exit 1; }
deb=$(ls "$work"/jointcomp_"$version"_*.deb)
echo "== $(basename "$deb")"
dpkg-deb --field "$deb" Package Version Architecture Depends
depends=$(dpkg-deb --field "$deb" Depends)
for needed in libc6 liburdfdom python3-numpy; do
  case "$depends" in *"$needed"*) ;; *) echo "Depends lacks $needed"; exit 1 ;; esac
done

dpkg-deb --extract "$deb" "$work/root"
root="$work/root"
# The library folder is GNUInstallDirs' (/usr/lib, or /usr/lib/<multiarch> when configured for /usr).
library=$(cd "$root" && find usr/lib -name libjointcomp.so.1 -print -quit)
[ -n "$library" ] || { echo "the package lacks libjointcomp.so.1"; dpkg-deb --contents "$deb"; exit 1; }
libdir=$(dirname "$library")
for file in usr/bin/jointcomp "$libdir/libjointcomp.so" usr/include/jointcomp/jointcomp.h \
  "$libdir/pkgconfig/jointcomp.pc" "$libdir/cmake/jointcomp/jointcompConfig.cmake" \
  usr/lib/python3/dist-packages/jointcomp/__init__.py usr/share/jointcomp/robots/rx170.urdf \
  usr/share/jointcomp/robots/ur10.urdf usr/share/jointcomp/params/rx170.json \
  usr/share/jointcomp/plots/plot_spiral_runs.py usr/share/jointcomp/fmu/jointcomp_fmi2.fmu \
  usr/share/jointcomp/fmu/jointcomp_fmi3.fmu usr/share/jointcomp/matlab/jointcomp_load.m \
  usr/share/jointcomp/fmu/binaries/linux64/jointcomp.so usr/share/jointcomp/fmu/binaries/x86_64-linux/jointcomp.so; do
  [ -e "$root/$file" ] || { echo "the package lacks /$file"; dpkg-deb --contents "$deb"; exit 1; }
done

echo "== the unpacked tool finds its files beside itself"
cd "$work/run"  # nowhere near a source tree
"$root/usr/bin/jointcomp" --version | tee "$work/version.txt"
grep -q "^jointcomp $version$" "$work/version.txt"
grep -qF "files: $(realpath "$root")/usr/share/jointcomp (installed)" "$work/version.txt"

echo "== it exports an FMU of a robot from the installed binaries"
"$root/usr/bin/jointcomp" export-fmu --urdf "$root/usr/share/jointcomp/robots/rx170.urdf" \
  --params "$root/usr/share/jointcomp/params/rx170.json" --fmi 3 --out "$work/run/rx170.fmu" | tee "$work/export.txt"
grep -q "FMI 3.0 co-simulation" "$work/export.txt"
# the listing is captured first: under pipefail, `unzip | grep -q` fails when grep exits early and unzip
# takes SIGPIPE (CI stop 46 failed so)
listing=$(unzip -l "$work/run/rx170.fmu")
grep -q "binaries/x86_64-linux/jointcomp.so" <<<"$listing"

echo "== it runs the main job and plots"
"$root/usr/bin/jointcomp" paper --out "$work/run/paper" | tee "$work/paper.txt"
grep -q "^stiffness and kinematic correction" "$work/paper.txt"
for output in spiral_runs.csv summary.json fmu/jointcomp_fmi2.fmu fmu/jointcomp_fmi3.fmu; do
  [ -s "$work/run/paper/$output" ] || { echo "paper did not write $output"; exit 1; }
done
# summary.json names the robot and the simulated robot that ran (the plant here, not "quasi-static")
/usr/bin/python3 - "$work/run/paper/summary.json" <<'PY'
import json
import sys

summary = json.load(open(sys.argv[1]))
assert summary["robot"] == "rx170", summary
assert "quasi-static" not in summary["experiment"], summary["experiment"]
assert summary["simulated_robot"].startswith("flexible-joint plant"), summary["simulated_robot"]
PY
if /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then
  [ -s "$work/run/paper/spiral_z_error.png" ] || { echo "no plot from the installed plot scripts"; exit 1; }
fi

echo "== the unpacked Python package loads the unpacked library"
env -u JOINTCOMP_LIBRARY PYTHONPATH="$root/usr/lib/python3/dist-packages" PYTHONDONTWRITEBYTECODE=1 \
  /usr/bin/python3 - "$root" "$version" <<'PY'
import sys

import numpy as np

import jointcomp

root, version = sys.argv[1:]
assert jointcomp.__file__.startswith(root), jointcomp.__file__
assert jointcomp.library_path.startswith(root), jointcomp.library_path
assert jointcomp.__version__ == version
with jointcomp.Robot(root + "/usr/share/jointcomp/robots/rx170.urdf", root + "/usr/share/jointcomp/params/rx170.json") as robot:
    q = np.array([0.0, -0.3, 1.9, 0.0, 0.4, 0.0])
    pose = robot.forward_kinematics(q)
    assert pose.shape == (4, 4) and np.isfinite(pose).all()
    errors = robot.predict_joint_errors(q)
    assert errors.shape == (6,) and np.isfinite(errors).all() and np.abs(errors).max() > 0
print("jointcomp", jointcomp.__version__, "library", jointcomp.library_path)
PY
