#!/usr/bin/env python3
# usage: JOINTCOMP_LIBRARY=.../libjointcomp.so /usr/bin/python3 make_tracker_export.py CAMPAIGN.csv URDF OUT.csv PYTHON_PACKAGE_DIR
# tracker export of a jointcomp campaign: joint_1..joint_N in degrees, the nominal target (nominal robot, the
# flange target) and the deviation measured - target in mm, ';' separated, a metadata preamble.
import sys, numpy as np
sys.path.insert(0, sys.argv[4])
import jointcomp
campaign, urdf, out = sys.argv[1:4]
rows = [l.rstrip("\n").split(",") for l in open(campaign) if not l.startswith("#")]
meta = {l[2:].split(":")[0]: l.split(":",1)[1].strip() for l in open(campaign) if l.startswith("# ")}
head, rows = rows[0], rows[1:]
target = np.array([float(v) for v in meta["target"].split(",")]) * 1e-3
robot = jointcomp.Robot(urdf)
n = robot.dof
with open(out, "w") as f:
    f.write("Tracker export\nInstrument;simulated\nUnits;deg;mm\n\n")
    f.write(";".join(["Point"] + [f"joint_{j+1}" for j in range(n)] + ["X_target", "Y_target", "Z_target", "dX", "dY", "dZ"]) + "\n")
    for k, r in enumerate(rows):
        q = np.array([float(r[head.index(f"q{j+1}")]) for j in range(n)])
        pose = robot.forward_kinematics(np.radians(q))
        nominal = (pose[:3, :3] @ target + pose[:3, 3]) * 1e3
        measured = np.array([float(r[head.index(c)]) for c in "xyz"])
        dev = measured - nominal
        f.write(";".join([str(k + 1)] + [f"{v:.4f}" for v in q] + [f"{v:.3f}" for v in nominal] + [f"{v:.4f}" for v in dev]) + "\n")
