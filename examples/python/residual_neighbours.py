"""Is what a calibration leaves systematic? For each row of a campaign, the residual (measured minus
predicted position) is compared with the mean residual of its nearest neighbours in joint space (leave one
out) and of the rows measured just before and after it. A residual that neighbours predict is a smooth
function of the pose (or of time), something a better model could capture; one they do not predict is
noise or non-repeatable motion. Neighbours measured close in time may agree because little changed in
between, not because the pose decides: the script also predicts from neighbours measured at least
--min-gap-s apart (the test that discovery's report applies, `unexplained.pose_predictability`).

Usage (after `jointcomp calibrate ... --out DIR`, which writes DIR/report.json, the calibrated URDF and
parameter file):
    /usr/bin/python3 examples/python/residual_neighbours.py DIR CAMPAIGN.csv

The figures quoted in the README for the IPA UR10 (Series A: 0.42 mm RMS; 0.19 mm left after three
neighbours at any time, but 0.35 mm after three measured at least 10 minutes apart) come from `jointcomp calibrate --urdf model/robots/ur10.urdf --campaign A.csv --out DIR`
then this script on DIR and A.csv.
"""

import argparse
import json
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "capi" / "python"))
import jointcomp  # noqa: E402  (the checkout's bindings, found after the path is set)


def rotation(vector):
    """Exp of a rotation vector (Rodrigues), as the calibration's frame rotation."""
    angle = np.linalg.norm(vector)
    if angle < 1e-15:
        return np.eye(3)
    k = vector / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def read_campaign(path):
    rows = [line.strip().split(",") for line in open(path) if not line.startswith("#")]
    header, values = rows[0], np.array(rows[1:], dtype=float)
    q = np.radians(values[:, [header.index("q%d" % j) for j in range(1, 7)]])
    measured = values[:, [header.index(axis) for axis in ("x", "y", "z")]] * 1e-3
    time = values[:, header.index("t")] if "t" in header else np.arange(len(values), dtype=float)
    return q, measured, time


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("calibration", help="the output folder of jointcomp calibrate")
    parser.add_argument("campaign", help="the campaign calibrated on (or one in the same instrument frame)")
    parser.add_argument("--neighbours", default="3,5,10,20", help="neighbour counts to try")
    parser.add_argument("--min-gap-s", type=float, default=600.0,
                        help="the second pass takes neighbours measured at least this long apart (s)")
    arguments = parser.parse_args()
    report = json.load(open(pathlib.Path(arguments.calibration) / "report.json"))
    value = {p["name"]: p["value"] for p in report["parameters"]}
    frame_rotation = rotation(np.array([value["frame.rx_rad"], value["frame.ry_rad"], value["frame.rz_rad"]]))
    frame_translation = np.array([value["frame.tx_m"], value["frame.ty_m"], value["frame.tz_m"]])
    target = np.array([value["target.x_m"], value["target.y_m"], value["target.z_m"]])
    # The calibrated URDF ends at a tool link at the fitted target (the parameter file's "tool" says so):
    # its forward kinematics already reach the measured point.
    if "tool" in json.load(open(report["outputs"]["parameters"])):
        target = np.zeros(3)
    q, measured, time = read_campaign(arguments.campaign)
    with jointcomp.Robot(report["outputs"]["urdf"], report["outputs"]["parameters"]) as robot:
        predicted = np.empty_like(measured)
        for k in range(len(q)):
            pose = robot.forward_kinematics(q[k] + robot.predict_joint_errors(q[k]))
            predicted[k] = frame_rotation @ (pose[:3, :3] @ target + pose[:3, 3]) + frame_translation
    residual = measured - predicted
    rms = lambda e: 1e3 * np.sqrt(np.mean(np.sum(e ** 2, axis=1)))  # noqa: E731
    print("%d rows, residual RMS %.4f mm" % (len(q), rms(residual)))
    scaled = q / np.std(q, axis=0).clip(1e-9)
    squared = np.sum(scaled ** 2, axis=1)
    for gap in (0.0, arguments.min_gap_s):
        for count in [int(c) for c in arguments.neighbours.split(",")]:
            left = np.empty_like(residual)
            scored = np.zeros(len(q), dtype=bool)
            for start in range(0, len(q), 1024):  # distances in blocks: memory stays small
                block = slice(start, min(start + 1024, len(q)))
                distance = squared[block, None] + squared[None, :] - 2 * scaled[block] @ scaled.T
                distance[np.arange(distance.shape[0]), np.arange(start, block.stop)] = np.inf
                distance[np.abs(time[block, None] - time[None, :]) < gap] = np.inf
                nearest = np.argpartition(distance, count, axis=1)[:, :count]
                scored[block] = np.isfinite(np.take_along_axis(distance, nearest, axis=1)).all(axis=1)
                left[block] = residual[block] - residual[nearest].mean(axis=1)
            label = " at least %.0f s apart" % gap if gap > 0 else ""
            if scored.sum() <= count:
                print("  no rows measured%s to predict from" % label)
                continue
            print("  left after the mean of the %2d nearest poses%s: %.4f mm of %.4f (noise alone: %.4f)"
                  % (count, label, rms(left[scored]), rms(residual[scored]),
                     rms(residual[scored]) * np.sqrt(1 + 1 / count)))
    in_time = residual[1:-1] - 0.5 * (residual[:-2] + residual[2:])
    print("  left after the mean of the rows just before and after: %.4f mm" % rms(in_time))


if __name__ == "__main__":
    main()
