"""Plots the 3-D error of every row before and after a kinematic calibration (jointcomp calibrate), per
campaign, and a histogram of the errors. usage: plot_calibration.py residuals.csv out.png
Runs on Debian's /usr/bin/python3 with python3-numpy and python3-matplotlib."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from atomic_png import save_figure  # noqa: E402  (a sibling of this script)


def read(csv_path):
    data = np.genfromtxt(csv_path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    return np.atleast_1d(data)


def main(csv_path, png_path):
    data = read(csv_path)
    campaigns = []
    for name, role in zip(data["campaign"], data["role"]):
        if (name, role) not in campaigns:
            campaigns.append((name, role))
    figure, axes = plt.subplots(len(campaigns), 2, figsize=(13, 0.6 + 3.8 * len(campaigns)), squeeze=False,
                             layout="constrained")
    for (name, role), (along, histogram) in zip(campaigns, axes):
        rows = data[(data["campaign"] == name) & (data["role"] == role)]
        before, after = rows["before_mm"], rows["after_mm"]
        rms_before, rms_after = np.sqrt(np.mean(before**2)), np.sqrt(np.mean(after**2))
        index = np.arange(len(rows))
        along.plot(index, before, ".", ms=1.5, color="tab:red", label=f"before: RMS {rms_before:.3f} mm")
        along.plot(index, after, ".", ms=1.5, color="tab:blue", label=f"after: RMS {rms_after:.3f} mm")
        down = rows["weight"] < 0.999
        if np.any(down):
            along.plot(index[down], after[down], "o", ms=3, mfc="none", color="black", lw=0.5,
                       label=f"down-weighted by the robust loss ({np.count_nonzero(down)})")
        along.set_yscale("log")
        along.set_xlabel("row (in file order)")
        along.set_ylabel("3-D error [mm]")
        along.set_title(f"{name} ({role}):\nerror per row", fontsize=10)
        along.legend(fontsize=8, markerscale=4)
        top = max(np.percentile(before, 99.5), after.max())
        bins = np.linspace(0.0, top, 80)
        histogram.hist(before, bins=bins, alpha=0.5, color="tab:red", label="before")
        histogram.hist(after, bins=bins, alpha=0.6, color="tab:blue", label="after")
        histogram.set_xlabel("3-D error [mm]")
        histogram.set_ylabel("rows")
        # Two lines: on one, long campaign names ran off the figure.
        histogram.set_title(f"{name}: histogram\nmean {np.mean(before):.3f} -> {np.mean(after):.3f} mm, "
                            f"max {before.max():.3f} -> {after.max():.3f} mm", fontsize=10)
        histogram.legend(fontsize=8)
    figure.suptitle("Kinematic calibration: before = nominal robot with the instrument frame fitted;\n"
                    "after = calibrated robot (held-out campaigns: frame re-fitted)", fontsize=10)
    save_figure(figure, png_path, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
