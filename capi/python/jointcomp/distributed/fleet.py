"""Fleet calibration: one campaign per robot, calibrated (or discovered) on a Dask cluster, a folder per
robot and a fleet summary with outliers flagged. Tasks carry the campaign files' contents (no shared file
system); a robot that fails, whatever the reason, is reported in the summary, which is always written."""

import contextlib
import csv
import io
import json
import os
import pathlib

import numpy as np

from .._paths import plain_file_name, prepare_output_folder, remove_stale_scratch_folders, scratch_folder
from . import streaming as _cluster
from .laws import DistributedError
from .results import save_figure, write_text

OUTLIER_RULE = "after-RMS above median + 3 x 1.4826 x MAD of the fleet's after-RMS"
_FLEET_FILES = ("fleet_summary.csv", "fleet_summary.json", "fleet_summary.txt", "fleet.png")
MAX_CAMPAIGN_BYTES = 256 << 20


class FleetResult:
    """What :func:`fleet` found: ``robots`` (one dict per campaign, in the order given: name, campaign,
    before / after / held-out errors in mm, outlier, error), the outlier ``threshold_mm`` and :meth:`summary`,
    :meth:`to_json`, :meth:`plot`."""

    def __init__(self, method, robots):
        self.method = method
        self.robots = robots
        after = np.array([r["after"]["rms_mm"] for r in robots if "after" in r])
        self.median_mm = float(np.median(after)) if after.size else float("nan")
        self.mad_mm = float(np.median(np.abs(after - self.median_mm))) if after.size else float("nan")
        self.threshold_mm = self.median_mm + 3.0 * 1.4826 * self.mad_mm
        for r in robots:
            r["outlier"] = "after" in r and r["after"]["rms_mm"] > self.threshold_mm

    @property
    def failed(self):
        """The robots whose calibration failed (their "error" says why)."""
        return [r for r in self.robots if "error" in r]

    def to_json(self):
        """The fleet summary as a JSON-ready dict (fleet_summary.json)."""
        return {"format": "jointcomp-fleet/1", "method": self.method, "robots": self.robots,
                "outlier_rule": OUTLIER_RULE, "median_after_rms_mm": _number(self.median_mm),
                "mad_after_rms_mm": _number(self.mad_mm), "outlier_threshold_mm": _number(self.threshold_mm),
                "outliers": [r["name"] for r in self.robots if r.get("outlier")],
                "failed": [r["name"] for r in self.failed]}

    def rows(self):
        """(header, rows) of the fleet table (fleet_summary.csv), one row per robot; the held-out columns
        give the RMS error of each held-out campaign after the fit, ";"-separated."""
        header = ["robot", "campaign", "before_mean_mm", "before_rms_mm", "before_max_mm", "after_mean_mm",
                  "after_rms_mm", "after_max_mm", "held_out_rms_mm", "outlier", "error"]
        rows = []
        for r in self.robots:
            b, a = r.get("before", {}), r.get("after", {})
            held = ";".join("%.4f" % h["rms_mm"] if isinstance(h.get("rms_mm"), (int, float)) else "?"
                            for h in r.get("held_out", []))
            rows.append([r["name"], r["campaign"]] + ["%.4f" % s[k] if k in s else "" for s in (b, a)
                                                      for k in ("mean_mm", "rms_mm", "max_mm")]
                        + [held, "yes" if r.get("outlier") else "no", r.get("error", "")])
        return header, rows

    def summary(self):
        """The fleet table as text, held-out errors, outliers and failures flagged, and the outlier rule."""
        _, rows = self.rows()
        lines = ["Fleet %s: %d robots, %d failed; errors of each robot's fitted campaign, mm" % (
            self.method, len(self.robots), len(self.failed)),
            "%-20s %10s %10s %10s %10s %14s  %s" % ("robot", "before RMS", "before max", "after RMS", "after max",
                                                     "held-out RMS", "")]
        for r in rows:
            flag = "OUTLIER" if r[9] == "yes" else ("FAILED: " + r[10] if r[10] else "")
            lines.append("%-20s %10s %10s %10s %10s %14s  %s" % (r[0], r[3], r[4], r[6], r[7], r[8] or "-", flag))
        lines.append("Outliers: %s (threshold %.4f mm)." % (OUTLIER_RULE, self.threshold_mm))
        return "\n".join(lines)

    def plot(self, path):
        """Each robot's RMS error before and after as bars, outliers marked, the threshold drawn (PNG)."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        good = [r for r in self.robots if "after" in r]
        x = np.arange(len(good))
        figure, axis = plt.subplots(figsize=(max(6, 0.6 * len(good) + 2), 4.5))
        axis.bar(x - 0.2, [r["before"]["rms_mm"] for r in good], 0.4, color="tab:red", label="before (RMS)")
        axis.bar(x + 0.2, [r["after"]["rms_mm"] for r in good], 0.4, color="tab:blue", label="after (RMS)")
        for k, r in zip(x, good):
            if r["outlier"]:
                axis.annotate("outlier", (k + 0.2, r["after"]["rms_mm"]), ha="center", va="bottom", fontsize=8)
        axis.axhline(self.threshold_mm, color="grey", linestyle="--", linewidth=0.8,
                     label="outlier threshold (median + 3 x 1.4826 x MAD)")
        axis.set_xticks(x)
        axis.set_xticklabels([r["name"] for r in good], rotation=45, ha="right", fontsize=8)
        axis.set_ylabel("fitted campaign RMS [mm]")
        axis.set_title("Fleet %s: each robot's error before and after" % self.method)
        axis.legend(fontsize=8)
        figure.tight_layout()
        save_figure(figure, path)
        plt.close(figure)

    def write(self, folder, details):
        """Each robot's folder (from the tasks' ``details``), the fleet summary files and the plot."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        for r, d in zip(self.robots, details):
            if "error" in d:
                continue
            robot_folder = folder / r["name"]
            robot_folder.mkdir(parents=True, exist_ok=True)
            write_text(robot_folder / "report.json", d["report"])
            write_text(robot_folder / "summary.txt", d["summary"])
            write_text(robot_folder / "calibrated.urdf", d["urdf"])
            write_text(robot_folder / "calibrated.json", d["parameters"])
        header, rows = self.rows()
        text = io.StringIO()
        writer = csv.writer(text)
        writer.writerow(header)
        writer.writerows(rows)
        write_text(folder / "fleet_summary.csv", text.getvalue())
        write_text(folder / "fleet_summary.json", json.dumps(self.to_json(), indent=2) + "\n")
        write_text(folder / "fleet_summary.txt", self.summary() + "\n")
        if any("after" in r for r in self.robots):
            self.plot(folder / "fleet.png")


def _number(value):
    return value if np.isfinite(value) else None


def _fleet_task(job, item):
    """One robot of a fleet: calibrate or discover on the campaign's text (written to a private temporary
    folder); the report, the summary and the corrected robot's files as text, the before / after errors.
    Any failure is the robot's, reported, never the fleet's."""
    jointcomp = _cluster.load_jointcomp()
    index, (campaign_path, campaign_text), holdout_files = item
    result = {"index": index}
    written = {}
    try:
        with contextlib.ExitStack() as stack:
            folder = stack.enter_context(scratch_folder("jointcomp-fleet-"))
            for k, (path, text) in enumerate([(campaign_path, campaign_text)] + list(holdout_files)):
                # Named as the user's file, so that the library's messages name it.
                local = os.path.join(folder, str(k), os.path.basename(path))
                os.makedirs(os.path.dirname(local))
                pathlib.Path(local).write_text(text, encoding="utf-8")
                written[local] = path
            campaign, *holdouts = list(written)
            nominal = stack.enter_context(jointcomp.Robot.from_text(job["urdf_text"], job["parameters_json"]))
            fit = jointcomp.discover if job["method"] == "discover" else jointcomp.calibrate
            robot, report = fit(nominal, campaign, holdouts=holdouts or None, **job["options"])
            with robot:
                robot.save(os.path.join(folder, "robot.urdf"), os.path.join(folder, "robot.json"))
                result["urdf"] = pathlib.Path(folder, "robot.urdf").read_text()
                result["parameters"] = pathlib.Path(folder, "robot.json").read_text()
            result["report"] = report.json
            result["summary"] = report.summary
            result["before"], result["after"], result["held_out"] = _before_after(report.data)
    except Exception as error:  # noqa: BLE001 - one robot's failure, whatever it is, is reported with it
        message = str(error)
        for local, path in written.items():
            message = message.replace(local, path)
        return {"index": index, "error": "%s: %.2000s" % (type(error).__name__, message)}
    return result


def _before_after(data):
    """The fitted campaign's errors (mm: mean, rms, max) before and after, and the held-out ones after."""
    def stats(s):
        return {"mean_mm": s["mean_mm"], "rms_mm": s["rms_mm"], "max_mm": s["max_mm"]}
    if data.get("format") == "jointcomp-discovery-report/1":
        held = [{"rms_mm": h.get("rms_mm")} for h in data["final"].get("held_out", []) if isinstance(h, dict)]
        return stats(data["initial"]["fitted"]), stats(data["final"]["fitted"]), held
    fitted = next(c for c in data["campaigns"] if c["role"] == "calibration")
    held = [stats(c["after"]) for c in data["campaigns"] if c["role"] != "calibration"]
    return stats(fitted["before"]), stats(fitted["after"]), held


def _read_campaign(path):
    path = pathlib.Path(path)
    if not path.is_file():
        raise DistributedError("campaign %s does not exist or is not a file" % path)
    if path.stat().st_size > MAX_CAMPAIGN_BYTES:
        raise DistributedError("campaign %s is larger than %d MB" % (path, MAX_CAMPAIGN_BYTES >> 20))
    return path.read_text(encoding="utf-8", errors="replace")


def _robot_names(campaigns):
    """A plain file name per campaign, never a summary file's, made unique."""
    names, taken = [], set(_FLEET_FILES)
    for campaign in campaigns:
        name = base = plain_file_name(pathlib.Path(campaign).stem)
        k = 1
        while name in taken:
            k += 1
            name = "%s_%d" % (base, k)
        taken.add(name)
        names.append(name)
    return names


def fleet(urdf, parameters, campaigns, out, *, method="calibrate", holdouts=None, options=None, client=None,
          scheduler=None, n_workers=None, serial=False, timeout=3600.0, start_timeout=30.0, retries=1,
          dashboard=None):
    """Calibrates (``method="calibrate"``) or runs discovery (``"discover"``) on each campaign file, one robot
    each, starting from the nominal ``urdf`` and ``parameters`` (path or JSON text). ``holdouts``: {campaign:
    [held-out files]} (optional); ``options``: keyword options of jointcomp.calibrate / discover. Writes
    ``out/<robot>/`` (report.json, summary.txt, calibrated.urdf, calibrated.json; the robot is named after
    its campaign file, made a plain file name) and ``out/fleet_summary.{csv,json,txt}`` and ``out/fleet.png``;
    returns a :class:`FleetResult`. ``out`` is checked (and created) before any work. A campaign that fails
    is reported in the summary with its reason, never fatal to the others."""
    from .montecarlo import _parameters_text, _read_text
    if method not in ("calibrate", "discover"):
        raise DistributedError("method is %r, must be \"calibrate\" or \"discover\"" % (method,))
    out = prepare_output_folder(out, DistributedError, "out")
    remove_stale_scratch_folders()  # what killed runs left, whether this one runs on a cluster or not
    campaigns = [str(c) for c in ([campaigns] if isinstance(campaigns, (str, os.PathLike)) else campaigns)]
    if not campaigns:
        raise DistributedError("campaigns: none given")
    holdouts = {str(k): [str(h) for h in v] for k, v in (holdouts or {}).items()}
    unknown = [k for k in holdouts if k not in campaigns]
    if unknown:
        raise DistributedError("holdouts: given for campaigns not in the fleet: %s" % ", ".join(unknown))
    job = {"urdf_text": _read_text(urdf, "urdf"), "parameters_json": _parameters_text(parameters),
           "method": method, "options": dict(options or {})}
    items = [(k, (c, _read_campaign(c)), [(h, _read_campaign(h)) for h in holdouts.get(c, [])])
             for k, c in enumerate(campaigns)]
    details = [None] * len(items)

    def keep(item, result):
        details[item[0]] = result
    stopped = None
    try:
        _run_fleet(job, items, keep, serial, client, scheduler, n_workers, timeout, start_timeout, retries, dashboard)
    except (DistributedError, KeyboardInterrupt) as error:
        stopped = error  # the summary is still written, the robots not done marked so
    for k, d in enumerate(details):
        if d is None:
            details[k] = {"error": "not run: %s" % (stopped or "stopped")}
    robots = []
    for name, campaign, d in zip(_robot_names(campaigns), campaigns, details):
        robot = {"name": name, "campaign": campaign}
        robot.update({key: d[key] for key in ("before", "after", "held_out", "error") if key in d})
        robots.append(robot)
    result = FleetResult(method, robots)
    result.write(out, details)
    if stopped is not None:
        kind = type(stopped) if isinstance(stopped, DistributedError) else DistributedError
        raise kind("%s (the fleet summary of the robots done is in %s)" % (stopped or "interrupted", out))
    return result


def _run_fleet(job, items, keep, serial, client, scheduler, n_workers, timeout, start_timeout, retries, dashboard):
    if serial:
        _cluster.stream(None, _fleet_task, job, items, keep, in_flight=1, timeout=timeout, retries=retries,
                        describe="fleet")
        return
    with _cluster.cluster(client, scheduler, n_workers, start_timeout, dashboard) as connected:
        _cluster.stream(connected, _fleet_task, job, items, keep, in_flight=max(4, len(items)), timeout=timeout,
                        retries=retries, describe="fleet", scheduler=scheduler)
