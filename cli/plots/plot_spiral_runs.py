"""Plots the Z deviation of the spiral runs (the nominal model's, and the identified model's corrections
dashed) along the path, in the manner of Fig. 13 of Olabi et al. (IEEE ICIT 2012). usage: plot_spiral_runs.py spiral_runs.csv out.png
Runs on Debian's /usr/bin/python3 with python3-numpy and python3-matplotlib."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from atomic_png import save_figure  # noqa: E402  (a sibling of this script)

NAMES = ["without correction", "stiffness correction", "stiffness and kinematic correction",
         "stiffness, kinematic and dynamic correction"]


def main(csv_path, png_path):
    data = np.genfromtxt(csv_path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    figure, (along, plan) = plt.subplots(1, 2, figsize=(13, 5.6), layout="constrained")
    # The nominal model's runs, and the identified model's corrections beside them (when it ran).
    for model in ("nominal", "identified"):
        for run, name in enumerate(NAMES):
            rows = data[(data["run"] == run) & (data["model"] == model)]
            if len(rows) == 0 or (model != "nominal" and run == 0):
                continue  # the dynamic correction's run is there only when asked for
            z = rows["error_z_mm"]
            label = name if model == "nominal" else f"{name}, identified model"
            along.plot(rows["t_s"], z, lw=0.7, ls="-" if model == "nominal" else "--",
                       label=f"{label}: Ra {np.mean(np.abs(z)):.4f} mm, Rz {np.ptp(z):.4f} mm")
    along.set_xlabel("time along the spiral [s]")
    along.set_ylabel("Z deviation [mm]")
    along.axhline(0.0, color="black", lw=0.5)
    # Below the axes: inside, it hid the deepest dips of the uncorrected run.
    along.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), frameon=False)
    along.set_title("Z deviation measured along the spiral")
    rows = data[(data["run"] == 0) & (data["model"] == "nominal")]
    points = plan.scatter(rows["planned_x_mm"], rows["planned_y_mm"], c=rows["error_z_mm"], s=2, cmap="coolwarm")
    figure.colorbar(points, ax=plan, label="Z deviation without correction [mm]")
    plan.set_aspect("equal")
    plan.set_xlabel("X [mm]")
    plan.set_ylabel("Y [mm]")
    plan.set_title("spiral in the XY plane")
    save_figure(figure, png_path, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
