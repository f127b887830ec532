"""Plot of `jointcomp discover`: RMS error after each accepted step (fitted, held-out, cross-validated).
Usage: /usr/bin/python3 plot_discovery.py steps.csv out.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from atomic_png import save_figure  # noqa: E402  (a sibling of this script)


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    steps = [int(r["step"]) for r in rows]
    labels = [r["effect"] for r in rows]

    def series(key):
        return [float(r[key]) if r[key] not in ("-", "") else float("nan") for r in rows]

    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(steps, series("fitted_rms_mm"), "o-", label="fitted RMS (3-D)")
    # One column per held-out campaign (heldout_rms_mm, heldout2_rms_mm, ...; none without one).
    for k, key in enumerate(key for key in rows[0] if key.startswith("heldout")):
        ax.plot(steps, series(key), "s-", label=f"held-out {k + 1} RMS (3-D)")
    ax.plot(steps, series("cv_rms_mm"), "^--", label="CV RMS per axis")
    ax.set_xticks(steps)
    ax.set_xticklabels(labels, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("error [mm]")
    ax.set_title("jointcomp discover: error after each accepted effect")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_figure(fig, sys.argv[2], dpi=120)


if __name__ == "__main__":
    main()
