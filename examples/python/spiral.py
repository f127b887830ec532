#!/usr/bin/env python3
"""The paper's spiral (Olabi et al., IEEE ICIT 2012, Table II) through the jointcomp Python bindings:
the three runs of a simulated RX170, their Ra and Rz, and a plot of the Z deviation along the path in the
manner of the paper's Fig. 13.

usage: /usr/bin/python3 examples/python/spiral.py [robot.urdf parameters.json] [--png out.png] [--quasi-static]

The bindings live in capi/python (found from this checkout automatically) and load libjointcomp.so as
described there (JOINTCOMP_LIBRARY, the system's library path, or this checkout's build trees).
"""

import argparse
import pathlib
import sys

checkout = pathlib.Path(__file__).resolve().parents[2]
try:
    import jointcomp
except ImportError:
    sys.path.insert(0, str(checkout / "capi" / "python"))
    import jointcomp

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the backend)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("urdf", nargs="?", default=str(checkout / "model" / "robots" / "rx170.urdf"))
    parser.add_argument("parameters", nargs="?", default=str(checkout / "model" / "params" / "rx170.json"))
    parser.add_argument("--png", default="spiral_z_error.png", help="where to write the plot")
    parser.add_argument("--quasi-static", action="store_true", help="simulate the quasi-static robot, not the plant")
    arguments = parser.parse_args()

    with jointcomp.Robot(arguments.urdf, arguments.parameters) as robot:
        use_plant = robot.has_drives and not arguments.quasi_static
        plan = robot.spiral_plan()
        result = robot.spiral_experiment(use_plant=use_plant, errors=True)

    print("jointcomp %s: the paper's spiral, simulated robot: %s"
          % (jointcomp.version(), "flexible-joint plant" if use_plant else "quasi-static"))
    print("%-36s %9s %9s" % ("run", "Ra [mm]", "Rz [mm]"))
    for name, metrics in zip(jointcomp.RUN_NAMES, result.metrics):
        print("%-36s %9.4f %9.4f" % (name, metrics.ra * 1e3, metrics.rz * 1e3))

    figure, axes = plt.subplots(figsize=(9, 4.5))
    for name, metrics, errors in zip(jointcomp.RUN_NAMES, result.metrics, result.errors):
        axes.plot(plan.time, errors[:, 2] * 1e3, linewidth=0.8,
                  label="%s (Ra %.4f mm, Rz %.4f mm)" % (name, metrics.ra * 1e3, metrics.rz * 1e3))
    axes.set_xlabel("time [s]")
    axes.set_ylabel("Z deviation [mm]")
    axes.set_title("The paper's spiral on a simulated %s" % ("RX170" if "rx170" in arguments.urdf else "robot"))
    axes.grid(True, linewidth=0.3)
    axes.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    figure.savefig(arguments.png, dpi=120, bbox_inches="tight")
    print("wrote %s" % arguments.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
