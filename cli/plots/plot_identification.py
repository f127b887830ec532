"""Plots an identification report of `jointcomp identify` in the manner of Olabi et al. (IEEE ICIT 2012):
stiffness (deflection against torque per joint, as their Fig. 9, and the local and global estimates with
their intervals side by side) or transmission error (the joint-2 sweep's errors against the joint angle,
as their Fig. 11, and the spectrum over orders of the stage angle).
usage: plot_identification.py report.json out.png
Runs on Debian's /usr/bin/python3 with python3-numpy and python3-matplotlib."""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from atomic_png import save_figure  # noqa: E402  (a sibling of this script)


def plot_stiffness(report, png_path):
    joints = report["joints"]
    figure = plt.figure(figsize=(14, 8.5))
    grid = figure.add_gridspec(3, 3, height_ratios=[1, 1, 1.1])
    for index, joint in enumerate(joints[:6]):
        axes = figure.add_subplot(grid[index // 3, index % 3])
        local = joint["local"]
        axes.set_title(joint["joint"], fontsize=10)
        if "torque_nm" not in local:
            axes.text(0.5, 0.5, local.get("reason", "not identified"), ha="center", va="center", wrap=True, fontsize=8,
                      transform=axes.transAxes)
            continue
        torque = np.array(local["torque_nm"])
        deflection = np.array(local["deflection_deg"]) * 1e3
        sigma = np.array(local["deflection_sigma_deg"]) * 1e3
        axes.errorbar(torque, deflection, yerr=sigma, fmt="o", ms=3, lw=0.8, label=f"measured ({local['method']})")
        if local.get("identified"):
            line = np.linspace(torque.min(), torque.max(), 50)
            k = local["stiffness_nm_per_rad"]
            low, high = local["stiffness_interval_nm_per_rad"]
            axes.plot(line, np.degrees(line / k) * 1e3, "r-", lw=1,
                      label=f"K = {k / 1e3:.1f} [{low / 1e3:.1f}, {high / 1e3 if high else math.inf:.1f}] kN m/rad")
        axes.set_xlabel("torque carried [N m]", fontsize=8)
        axes.set_ylabel("deflection [1e-3 deg]", fontsize=8)
        axes.tick_params(labelsize=7)
        axes.legend(fontsize=7)
    compare = figure.add_subplot(grid[2, :])
    names = [j["joint"] for j in joints]
    x = np.arange(len(names))
    for offset, method, colour in ((-0.15, "local", "tab:blue"), (0.15, "global", "tab:orange")):
        values, lower, upper = [], [], []
        for joint in joints:
            estimate = joint[method]
            reference = joint.get("true_stiffness_nm_per_rad") or joint["local"].get("stiffness_nm_per_rad") or 1.0
            if estimate.get("identified"):
                k = estimate["stiffness_nm_per_rad"] / reference
                low, high = estimate["stiffness_interval_nm_per_rad"]
                values.append(k)
                lower.append(k - low / reference)
                upper.append((high / reference - k) if high is not None else 1.0)
            else:
                values.append(np.nan)
                lower.append(0.0)
                upper.append(0.0)
        compare.errorbar(x + offset, values, yerr=[lower, upper], fmt="o", capsize=4, color=colour, label=method)
    reference_name = "the true stiffness" if "true_stiffness_nm_per_rad" in joints[0] else "the local estimate"
    compare.axhline(1.0, color="black", lw=0.6)
    compare.set_xticks(x)
    compare.set_xticklabels(names)
    compare.set_ylabel(f"K / {reference_name}")
    compare.set_title(f"local and global estimates with their {report['confidence'] * 100:.0f} % intervals")
    compare.legend(fontsize=8)
    figure.suptitle("joint stiffness identification: " + report["sources"]["campaign"], fontsize=11)
    figure.tight_layout()
    save_figure(figure, png_path, dpi=110)


def plot_transmission(report, png_path):
    series = report["series"]
    command = np.array(series["command_deg"])
    figure, (sweep, spectrum) = plt.subplots(2, 1, figsize=(12, 8.5))
    sweep.plot(command, np.array(series["stiffness_error_deg"]) * 1e3, color="tab:gray", lw=1,
               label="predicted stiffness error")
    sweep.plot(command, np.array(series["kinematic_error_deg"]) * 1e3, ".", ms=2, color="tab:blue",
               label="measured minus stiffness error: kinematic error")
    sweep.plot(command, np.array(series["fitted_deg"]) * 1e3, color="tab:red", lw=0.9, label="baseline and harmonics fitted")
    sweep.set_xlabel(f"{report['joint']} commanded angle [deg]")
    sweep.set_ylabel("error [1e-3 deg]")
    sweep.legend(fontsize=8)
    sweep.set_title(f"sweep of {report['joint']}: {report['samples']} points, "
                    f"{report['stage_revolutions']:.1f} revolutions of {report['of']}")
    orders = np.array(report["spectrum"]["cycles_per_revolution"])
    amplitude = np.array(report["spectrum"]["amplitude_deg"]) * 1e3
    spectrum.plot(orders, amplitude, color="tab:blue", lw=1, label="single-harmonic amplitude (periodogram)")
    for h in report["harmonics"]:
        low, high = h["amplitude_interval_deg"]
        a = h["amplitude_deg"]
        spectrum.errorbar([h["cycles_per_revolution"]], [a * 1e3], yerr=[[(a - low) * 1e3], [(high - a) * 1e3]], fmt="o",
                          color="tab:red", capsize=4)
        spectrum.annotate(f"{h['cycles_per_revolution']:g}: {a * 1e3:.2f}e-3 deg, phase {h['phase_rad']:+.2f} rad",
                          (h["cycles_per_revolution"], a * 1e3), textcoords="offset points", xytext=(6, 6), fontsize=8)
        if "true_amplitude_deg" in h:
            spectrum.plot([h["cycles_per_revolution"]], [h["true_amplitude_deg"] * 1e3], "kx", ms=8)
    spectrum.set_xlabel(f"cycles per revolution of {report['of']}")
    spectrum.set_ylabel("amplitude [1e-3 deg]")
    spectrum.set_title("spectrum of the kinematic error (red: significant harmonics with their intervals; x: truth)")
    spectrum.legend(fontsize=8)
    figure.tight_layout()
    save_figure(figure, png_path, dpi=110)


def main(report_path, png_path):
    with open(report_path, encoding="utf-8") as handle:
        report = json.load(handle)
    if report["identification"] == "stiffness":
        plot_stiffness(report, png_path)
    else:
        plot_transmission(report, png_path)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
