"""Past one machine: Monte Carlo accuracy with confidence bands, and fleet calibration, on Dask.

Two jobs, each spread over a Dask cluster (a ``client=`` you give, a scheduler address, or a LocalCluster
of worker processes started here):

* :func:`monte_carlo` draws N parameter sets from a distribution (the uncertainty an identification,
  calibration or discovery report states, the main job's perturbation, or your own), and for each runs the
  paper's spiral compensated with the NOMINAL parameters on a simulated robot whose truth is the DRAWN set
  (``jc_spiral_experiment_truth``). It reports percentiles of Ra, Rz, RMS and max error, the bound each
  stays within in 95 % of the draws, and the error band along the path (:class:`MonteCarloResult`).
* :func:`fleet` calibrates (or runs discovery on) many campaign files, one robot each: a report folder per
  robot and a fleet summary with outliers flagged (:class:`FleetResult`).

Only inputs (paths, JSON text, seeds) and results (plain numbers, lists and dicts) travel between the
client and the workers: every task loads its own library and robots, no ctypes handle is ever shipped.
Draw k of seed s comes from its own generator, ``numpy.random.Generator(PCG64(SeedSequence([s, k])))``,
so the results do not depend on the number of workers or on the order the tasks run.

Command line: ``/usr/bin/python3 -m jointcomp.distributed montecarlo|fleet ...`` (what ``jointcomp
montecarlo`` and ``jointcomp fleet`` run); ``--help`` lists the options.
"""

import argparse
import concurrent.futures
import contextlib
import csv
import io
import json
import math
import os
import pathlib
import re
import signal
import sys
import tempfile
import xml.etree.ElementTree as ElementTree

import numpy as np

from ._paths import plain_file_name, prepare_output_folder, write_atomically
from .errors import JointcompError

DEFAULT_SEED = 2019
PERCENTILES = (5, 50, 95)
METRIC_NAMES = ("ra", "rz", "rms", "max")  # of the five jc_spiral_experiment metrics, the ones reported
RUN_KEYS = ("uncompensated", "stiffness", "compensated")  # the spiral's three runs (jointcomp.RUN_NAMES)
MAX_SAMPLES = 10000  # each draw keeps its error along the path (about 100 kB); jointcomp montecarlo's cap too
OUTLIER_RULE = "after-RMS above median + 3 x 1.4826 x MAD of the fleet's after-RMS"


class DistributedError(RuntimeError):
    """A Monte Carlo or fleet run that cannot go on: bad input, a cluster that does not start, a timeout."""


# ---- Parameter distributions ------------------------------------------------------------------------------
# A distribution is a list of entries, each one parameter and its law (plain dicts: they are JSON files too):
#   {"parameter": NAME, "law": "normal" | "uniform", "scale": S, "relative": false, "source": "..."}
# normal: value + S * N(0, 1); uniform: value + S * U(-1, 1); relative: value * (1 + S * draw). NAME is
#   joint_J.stiffness_nm_per_rad        the compliance effect's stiffness of joint J
#   joint_J.compliance_rad_per_nm       the same as a compliance (1 / stiffness), as calibration reports it
#   joint_J.harmonic_<of>_x<order>.amplitude_rad | .phase_rad   a transmission-error harmonic
#   joint_J.offset_rad, joint_J.placement_{dx,dy,dz}_m, joint_J.placement_{rx,ry,rz}_rad
#                                       the geometry (URDF joint origin: origin * Trans(d) * Exp(r) * Rot(axis, offset))
#   effects/<i>/<key>[/<k>]             any number of the parameter file's effect i, by its JSON path
# Geometry entries draw a deviation from the URDF as it is (their value is 0 there).
# One more kind of entry correlates normal entries (a calibration report gives it from the fit's covariance):
#   {"correlation": {"parameters": [NAME, ...], "matrix": [[1, r12, ...], ...]}}
# Their standard normal draws are then mixed by a square root of that matrix before their scales apply.

_GEOMETRY = re.compile(r"^(?P<joint>[^.]+)\.(?P<what>offset_rad|placement_(?:dx|dy|dz)_m|placement_(?:rx|ry|rz)_rad)$")
_STIFFNESS = re.compile(r"^(?P<joint>[^.]+)\.(?P<what>stiffness_nm_per_rad|compliance_rad_per_nm)$")
_HARMONIC = re.compile(r"^(?P<joint>[^.]+)\.harmonic_(?P<of>.+)_x(?P<order>[0-9.eE+-]+)\.(?P<what>amplitude_rad|phase_rad)$")
_PATH = re.compile(r"^effects/(?P<index>[0-9]+)/(?P<key>[A-Za-z0-9_]+)(?:/(?P<item>[0-9]+))?$")
_DEG = math.pi / 180.0


def _entry(parameter, law, scale, relative, source):
    return {"parameter": parameter, "law": law, "scale": float(scale), "relative": bool(relative), "source": source}


def _joint_names(parameters, urdf_text):
    """The robot's moving joints in chain order: the parameter file's gear list, else the URDF's."""
    gears = parameters.get("gears", {}).get("joints")
    if gears:
        return [g["joint"] for g in gears]
    if urdf_text is None:
        return None
    root = ElementTree.fromstring(urdf_text)
    return [j.get("name") for j in root.iter("joint") if j.get("type") not in ("fixed", "floating", "planar")]


def _effect(parameters, effect_type):
    for effect in parameters.get("effects", []):
        if effect.get("type") == effect_type:
            return effect
    return None


def main_job_distribution(parameters_json):
    """The main job's perturbation of the truth (README, "The main job"; model/effects/perturbation.hpp) as
    a distribution: every stiffness x (1 + U(-5 %, 5 %)), every harmonic amplitude x (1 + U(-10 %, 10 %)),
    every phase + U(-0.1, 0.1) rad, the spring balancer's other values x (1 + U(-2 %, 2 %)). Effects of
    other types are not varied (the result lists them)."""
    parameters = json.loads(parameters_json)
    entries = []
    for i, effect in enumerate(parameters.get("effects", [])):
        kind = effect.get("type")
        if kind == "compliance":
            for k, _ in enumerate(effect.get("stiffness_nm_per_rad", [])):
                entries.append(_entry("effects/%d/stiffness_nm_per_rad/%d" % (i, k), "uniform", 0.05, True, "main job"))
        elif kind == "transmission_error":
            for k, h in enumerate(effect.get("harmonics", [])):
                name = "%s.harmonic_%s_x%g" % (h["joint"], h.get("of", "output"), h["cycles_per_revolution"])
                entries.append(_entry(name + ".amplitude_rad", "uniform", 0.10, True, "main job"))
                entries.append(_entry(name + ".phase_rad", "uniform", 0.10, False, "main job"))
        elif kind == "spring_balancer":
            for key, value in effect.items():
                if isinstance(value, (int, float)) and not isinstance(value, bool):
                    scale = 0.05 if key.endswith("stiffness_n_per_m") else 0.02
                    entries.append(_entry("effects/%d/%s" % (i, key), "uniform", scale, True, "main job"))
    return entries


def report_distribution(report):
    """The distribution a report states: ``(entries, not_propagated)``. ``report``: a jointcomp.Report, its
    JSON text or dict, or the path of a report.json. Every estimate with a standard error becomes a normal
    law around the identified value (the parameters must be the identified ones: the report's robot).
    Reports: stiffness and transmission-error identification (identify), calibration (its identified
    parameters; the instrument frame and target are the set-up's, not the robot's, and are listed in
    not_propagated) and discovery (the discovered effects' parameters). A calibration report's correlation
    (from the fit's covariance) comes along as a correlation entry over the propagated parameters; the
    other reports give standard errors only."""
    data = _report_data(report)
    entries, left = [], []
    kind = data.get("format") or data.get("identification")
    if kind == "stiffness":
        method = data.get("parameter_file_uses", "local")
        for joint in data.get("joints", []):
            estimate = joint.get(method, {})
            if estimate.get("identified") and estimate.get("stiffness_se_nm_per_rad"):
                entries.append(_entry(joint["joint"] + ".stiffness_nm_per_rad", "normal",
                                      estimate["stiffness_se_nm_per_rad"], False, "stiffness identification"))
            else:
                left.append(joint["joint"] + ".stiffness_nm_per_rad: not identified")
    elif kind == "transmission_error":
        for h in data.get("harmonics", []):
            name = "%s.harmonic_%s_x%g" % (data["joint"], data["of"], h["cycles_per_revolution"])
            if not h.get("significant", True):
                left.append(name + ": not significant (not in the parameter file)")
                continue
            entries.append(_entry(name + ".amplitude_rad", "normal", h["amplitude_se_deg"] * _DEG, False,
                                  "transmission-error identification"))
            entries.append(_entry(name + ".phase_rad", "normal", h["phase_se_rad"], False,
                                  "transmission-error identification"))
    elif kind == "jointcomp-calibration-report/1":
        for p in data.get("parameters", []):
            if not p.get("identified") or "sigma" not in p:
                continue
            if _GEOMETRY.match(p["name"]) or _STIFFNESS.match(p["name"]) or _HARMONIC.match(p["name"]):
                entries.append(_entry(p["name"], "normal", p["sigma"], False, "calibration"))
            else:
                left.append(p["name"] + ": of the measurement set-up, not the robot")
    elif kind == "jointcomp-discovery-report/1":
        for step in data.get("steps", []):
            for p in step.get("parameters", []):
                name, sigma = p["name"], p.get("sigma")
                if sigma and (_GEOMETRY.match(name) or _STIFFNESS.match(name) or _HARMONIC.match(name)):
                    entries.append(_entry(name, "normal", sigma, False, "discovery step %d" % step["step"]))
                else:
                    left.append(name + ": no law for this parameter type")
    else:
        raise DistributedError("report: %r is not a report jointcomp knows (identification, calibration or "
                               "discovery)" % (kind,))
    if not entries:
        raise DistributedError("report: it states no parameter with a standard error that could be propagated"
                               + (" (%s)" % "; ".join(left) if left else ""))
    correlation = data.get("correlation")
    if correlation:
        # The block of the propagated parameters (a principal block of a correlation matrix is one too).
        names = [e["parameter"] for e in entries]
        where = {name: k for k, name in enumerate(correlation["parameters"])}
        kept = [name for name in names if name in where]
        if len(kept) > 1:
            matrix = [[correlation["matrix"][where[a]][where[b]] for b in kept] for a in kept]
            entries.append({"correlation": {"parameters": kept, "matrix": matrix}})
    return check_distribution(entries, "report"), left


def _report_data(report):
    if hasattr(report, "data"):
        return report.data
    if isinstance(report, dict):
        return report
    if isinstance(report, (str, os.PathLike)) and not str(report).lstrip().startswith("{"):
        path = pathlib.Path(report)
        if not path.is_file():
            raise DistributedError("report: %s does not exist or is not a file" % path)
        try:
            return json.loads(path.read_text())
        except ValueError as error:
            raise DistributedError("report: %s is not JSON: %s" % (path, error)) from None
    return json.loads(report)


def load_distribution(path):
    """A distribution from a JSON file: a list of entries (see the module's comments), checked."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise DistributedError("distribution: %s does not exist or is not a file" % path)
    try:
        entries = json.loads(path.read_text())
    except ValueError as error:
        raise DistributedError("distribution: %s is not JSON: %s" % (path, error)) from None
    return check_distribution(entries, str(path))


def check_distribution(entries, where="distribution"):
    """``entries`` (a list of dicts) checked and completed; DistributedError names the entry at fault."""
    if not isinstance(entries, list) or not entries:
        raise DistributedError("%s: must be a non-empty list of {parameter, law, scale[, relative]}" % where)
    checked = []
    correlations = []
    for k, e in enumerate(entries):
        if isinstance(e, dict) and "correlation" in e:
            correlations.append((k, e["correlation"]))
            continue
        if not isinstance(e, dict) or "parameter" not in e or "scale" not in e:
            raise DistributedError("%s: entry %d needs \"parameter\" and \"scale\": %r" % (where, k, e))
        law = e.get("law", "normal")
        scale = e["scale"]
        if law not in ("normal", "uniform"):
            raise DistributedError("%s: entry %d (%s): law %r must be \"normal\" or \"uniform\"" % (
                where, k, e["parameter"], law))
        if not isinstance(scale, (int, float)) or not math.isfinite(scale) or scale < 0:
            raise DistributedError("%s: entry %d (%s): scale %r must be a finite number >= 0" % (
                where, k, e["parameter"], scale))
        name = e["parameter"]
        if not (_GEOMETRY.match(name) or _STIFFNESS.match(name) or _HARMONIC.match(name) or _PATH.match(name)):
            raise DistributedError("%s: entry %d: parameter %r is none of joint_J.stiffness_nm_per_rad, "
                                   "joint_J.compliance_rad_per_nm, joint_J.harmonic_<of>_x<order>.amplitude_rad|"
                                   "phase_rad, joint_J.offset_rad, joint_J.placement_<d|r><x|y|z>_<m|rad>, "
                                   "effects/<i>/<key>[/<k>]" % (where, k, name))
        checked.append(_entry(name, law, scale, e.get("relative", False), e.get("source", where)))
    if not checked:
        raise DistributedError("%s: no parameter entry (only correlations)" % where)
    for k, correlation in correlations:
        checked.append(_check_correlation(correlation, checked, "%s: entry %d (correlation)" % (where, k)))
    return checked


def _check_correlation(correlation, entries, where):
    """A correlation entry checked, with the matrix's square root (``factor``) the draws are mixed by."""
    if not isinstance(correlation, dict) or "parameters" not in correlation or "matrix" not in correlation:
        raise DistributedError("%s: needs \"parameters\" and \"matrix\"" % where)
    names = correlation["parameters"]
    laws = {e["parameter"]: e["law"] for e in entries if "parameter" in e}
    if not isinstance(names, list) or len(names) < 2 or len(set(names)) != len(names):
        raise DistributedError("%s: \"parameters\" must list two or more different parameters" % where)
    for name in names:
        if laws.get(name) != "normal":
            raise DistributedError("%s: %r is not a normal entry of the distribution" % (where, name))
    try:
        matrix = np.array(correlation["matrix"], dtype=float)
    except (TypeError, ValueError):
        raise DistributedError("%s: \"matrix\" is not a matrix of numbers" % where) from None
    n = len(names)
    if matrix.shape != (n, n) or not np.all(np.isfinite(matrix)):
        raise DistributedError("%s: \"matrix\" must be %d x %d and finite" % (where, n, n))
    if not np.allclose(matrix, matrix.T, atol=1e-9) or not np.allclose(np.diag(matrix), 1.0, atol=1e-9):
        raise DistributedError("%s: \"matrix\" must be symmetric with ones on its diagonal" % where)
    values, vectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    if values.min() < -1e-6:
        raise DistributedError("%s: \"matrix\" is not a correlation matrix (eigenvalue %.3g)" % (
            where, values.min()))
    factor = vectors * np.sqrt(np.clip(values, 0.0, None))  # factor @ factor.T == matrix
    return {"correlation": {"parameters": list(names), "matrix": matrix.tolist(), "factor": factor.tolist()}}


def sample_generator(seed, index):
    """Draw ``index``'s own generator: independent of how many draws there are and of who runs them."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), int(index)])))


def draw_parameters(parameters_json, urdf_text, distribution, seed, index):
    """Parameter set ``index`` of ``seed``: ``(parameters_json, urdf_text or None, clamped)``. The URDF comes
    back only when a geometry parameter is drawn; ``clamped`` counts stiffnesses drawn at or below zero,
    held at 1 % of their value."""
    generator = sample_generator(seed, index)
    correlations = [e["correlation"] for e in distribution if "correlation" in e]
    distribution = [e for e in distribution if "parameter" in e]
    draws = [generator.standard_normal() if e["law"] == "normal" else generator.uniform(-1.0, 1.0)
             for e in distribution]  # every draw first, in the distribution's order
    position = {e["parameter"]: k for k, e in enumerate(distribution)}
    for correlation in correlations:
        block = [position[name] for name in correlation["parameters"]]
        mixed = np.array(correlation["factor"]) @ np.array([draws[k] for k in block])
        for k, value in zip(block, mixed):
            draws[k] = float(value)
    parameters = json.loads(parameters_json)
    joints = None
    urdf = None
    clamped = 0

    def moved(value, entry, draw):
        return value * (1.0 + entry["scale"] * draw) if entry["relative"] else value + entry["scale"] * draw

    for entry, draw in zip(distribution, draws):
        name = entry["parameter"]
        match = _PATH.match(name)
        if match:
            effects = parameters.get("effects", [])
            index_ = int(match["index"])
            if index_ >= len(effects) or match["key"] not in effects[index_]:
                raise DistributedError("distribution: %s: the parameter file has no such value" % name)
            holder, key = effects[index_], match["key"]
            if match["item"] is not None:
                holder, key = holder[key], int(match["item"])
                if key >= len(holder):
                    raise DistributedError("distribution: %s: the parameter file has no such value" % name)
            value = moved(float(holder[key]), entry, draw)
            if "stiffness" in str(match["key"]) and value <= 0.0:
                value, clamped = 0.01 * float(holder[key]), clamped + 1
            holder[key] = value
            continue
        match = _STIFFNESS.match(name)
        if match:
            effect = _effect(parameters, "compliance")
            if joints is None:
                joints = _joint_names(parameters, urdf_text)
            if effect is None or joints is None or match["joint"] not in joints:
                raise DistributedError("distribution: %s: the parameters have no compliance of that joint" % name)
            k = joints.index(match["joint"])
            stiffness = float(effect["stiffness_nm_per_rad"][k])
            if match["what"] == "stiffness_nm_per_rad":
                value = moved(stiffness, entry, draw)
            else:
                compliance = moved(1.0 / stiffness, entry, draw)
                value = 1.0 / compliance if compliance > 0.0 else -1.0
            if value <= 0.0:
                value, clamped = 0.01 * stiffness, clamped + 1
            effect["stiffness_nm_per_rad"][k] = value
            continue
        match = _HARMONIC.match(name)
        if match:
            effect = _effect(parameters, "transmission_error")
            found = None
            for h in (effect or {}).get("harmonics", []):
                if (h["joint"] == match["joint"] and h.get("of", "output") == match["of"]
                        and abs(float(h["cycles_per_revolution"]) - float(match["order"])) < 1e-9):
                    found = h
            if found is None:
                raise DistributedError("distribution: %s: the parameters have no such harmonic" % name)
            if match["what"] == "amplitude_rad":
                if "amplitude_rad" in found:
                    found["amplitude_rad"] = moved(float(found["amplitude_rad"]), entry, draw)
                else:
                    found["amplitude_deg"] = moved(float(found["amplitude_deg"]) * _DEG, entry, draw) / _DEG
            else:
                found["phase_rad"] = moved(float(found["phase_rad"]), entry, draw)
            continue
        match = _GEOMETRY.match(name)
        if match:
            if urdf is None:
                urdf = _Geometry(urdf_text)
            urdf.move(match["joint"], match["what"], moved(0.0, entry, draw), name)
            continue
        raise DistributedError("distribution: %s: unknown parameter" % name)
    return json.dumps(parameters), (None if urdf is None else urdf.text()), clamped


def _rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _matrix_rpy(m):
    pitch = math.atan2(-m[2, 0], math.hypot(m[0, 0], m[1, 0]))
    return math.atan2(m[2, 1], m[2, 2]), pitch, math.atan2(m[1, 0], m[0, 0])


def _rotation(axis, angle):
    axis = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(axis)
    if angle == 0.0 or norm == 0.0:
        return np.eye(3)
    k = axis / norm
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


class _Geometry:
    """A URDF whose joint origins move as calibration parameterises them."""

    def __init__(self, text):
        if text is None:
            raise DistributedError("distribution: geometry parameters need the URDF")
        self.root = ElementTree.fromstring(text)

    def move(self, joint_name, what, amount, name):
        joint = next((j for j in self.root.iter("joint") if j.get("name") == joint_name), None)
        if joint is None:
            raise DistributedError("distribution: %s: the URDF has no joint %r" % (name, joint_name))
        origin = joint.find("origin")
        if origin is None:
            origin = ElementTree.SubElement(joint, "origin")
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        rotation = _rpy_matrix(*[float(v) for v in origin.get("rpy", "0 0 0").split()])
        axis_element = joint.find("axis")
        axis = [float(v) for v in axis_element.get("xyz").split()] if axis_element is not None else [1.0, 0.0, 0.0]
        if what == "offset_rad":
            rotation = rotation @ _rotation(axis, amount)
        elif what.endswith("_m"):
            xyz = xyz + rotation @ np.eye(3)["xyz".index(what[-3])] * amount
        else:
            rotation = rotation @ _rotation(np.eye(3)["xyz".index(what[-5])], amount)
        origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
        origin.set("rpy", " ".join(repr(float(v)) for v in _matrix_rpy(rotation)))

    def text(self):
        return ElementTree.tostring(self.root, encoding="unicode")


# ---- The tasks: run on the workers, plain data in and out ---------------------------------------------------

def _spiral_task(job, index):
    """Draw ``index`` of ``job`` (a dict of paths, JSON text, seed and options): the spiral compensated with
    the nominal parameters, followed by the drawn robot. Returns plain numbers and lists."""
    marker = job.get("kill_marker")
    if marker and index == job.get("kill_index", 0) and not os.path.exists(marker):
        pathlib.Path(marker).write_text("killed once\n")  # a test's worker dies here the first time only
        os.kill(os.getpid(), signal.SIGKILL)
    import jointcomp  # each worker loads its own library
    parameters, urdf_text, clamped = draw_parameters(job["parameters_json"], job["urdf_text"],
                                                     job["distribution"], job["seed"], index)
    result = {"index": index, "clamped": clamped}
    try:
        with contextlib.ExitStack() as stack:
            nominal = stack.enter_context(jointcomp.Robot.from_json(job["urdf"], job["parameters_json"]))
            truth_urdf = job["urdf"]
            if urdf_text is not None:
                folder = stack.enter_context(tempfile.TemporaryDirectory(prefix="jointcomp-mc-"))
                truth_urdf = os.path.join(folder, "truth.urdf")
                pathlib.Path(truth_urdf).write_text(urdf_text)
            truth = stack.enter_context(jointcomp.Robot.from_json(truth_urdf, parameters))
            experiment = nominal.spiral_experiment(use_plant=job["use_plant"], errors=True, truth=truth)
    except JointcompError as error:
        result["error"] = "%s: %s" % (type(error).__name__, error)
        return result
    stride = job["stride"]
    errors = experiment.errors[:, ::stride, :]
    result["metrics"] = [[m.ra, m.rz, m.rms, m.max, m.mean] for m in experiment.metrics]
    result["z"] = errors[:, :, 2].tolist()
    result["norm"] = np.linalg.norm(errors, axis=2).tolist()
    return result


def _no_op(x):
    """The bench's task: its round trip is the scheduler's overhead."""
    return x


def _fleet_task(job, campaign, holdouts):
    """One robot of a fleet: calibrate or discover on ``campaign``; the report, the summary and the
    corrected robot's files as text, and the before / after errors."""
    import jointcomp
    result = {"campaign": campaign}
    try:
        with jointcomp.Robot(job["urdf"], parameters_json=job["parameters_json"]) as nominal:
            if job["method"] == "discover":
                robot, report = jointcomp.discover(nominal, campaign, holdouts=holdouts or None, **job["options"])
            else:
                robot, report = jointcomp.calibrate(nominal, campaign, holdouts=holdouts or None, **job["options"])
            with robot, tempfile.TemporaryDirectory(prefix="jointcomp-fleet-") as folder:
                robot.save(os.path.join(folder, "robot.urdf"), os.path.join(folder, "robot.json"))
                result["urdf"] = pathlib.Path(folder, "robot.urdf").read_text()
                result["parameters"] = pathlib.Path(folder, "robot.json").read_text()
    except JointcompError as error:
        result["error"] = "%s: %s" % (type(error).__name__, error)
        return result
    result["report"] = report.json
    result["summary"] = report.summary
    result["before"], result["after"], result["held_out"] = _before_after(report.data)
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


# ---- The cluster ------------------------------------------------------------------------------------------

@contextlib.contextmanager
def cluster(client=None, scheduler=None, n_workers=None, start_timeout=60.0):
    """A Dask client: ``client`` as given, one connected to ``scheduler`` (an address such as
    tcp://host:8786), or a LocalCluster of ``n_workers`` single-threaded worker processes (default: the
    machine's cores) started here and closed on leaving. Starting or connecting takes at most
    ``start_timeout`` seconds, or DistributedError says so."""
    if client is not None:
        yield client
        return
    try:
        import distributed
    except ImportError:
        raise DistributedError("Dask's distributed package is missing: apt-get install python3-distributed "
                               "python3-dask (packaging/install-deps.sh)") from None
    if scheduler:
        try:
            connected = distributed.Client(scheduler, timeout=start_timeout, set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise DistributedError("scheduler %s: no connection within %g s (%s)" % (
                scheduler, start_timeout, error)) from None
        with connected:
            yield connected
        return
    n_workers = n_workers or os.cpu_count() or 1
    if n_workers < 1:
        raise DistributedError("n_workers is %d, must be at least 1" % n_workers)
    _export_environment()
    pool = concurrent.futures.ThreadPoolExecutor(1)
    started = pool.submit(distributed.LocalCluster, n_workers=n_workers, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=40)
    try:
        local = started.result(timeout=start_timeout)
    except concurrent.futures.TimeoutError:
        raise DistributedError("the local cluster of %d workers did not start within %g s" % (
            n_workers, start_timeout)) from None
    finally:
        pool.shutdown(wait=False)
    try:
        with distributed.Client(local, set_as_default=False) as connected:
            yield connected
    finally:
        local.close()


def _export_environment():
    """Local workers are new processes: they find this package and the library this process loaded."""
    import jointcomp
    package_root = str(pathlib.Path(jointcomp.__file__).resolve().parent.parent)
    paths = os.environ.get("PYTHONPATH", "").split(os.pathsep)
    if package_root not in paths:
        os.environ["PYTHONPATH"] = os.pathsep.join([package_root] + [p for p in paths if p])
    os.environ.setdefault("JOINTCOMP_LIBRARY", str(jointcomp.library_path))


def _run_tasks(client, function, job, items, timeout, retries, describe):
    """``function(job, *item)`` for every item, on the cluster (``client``) or here (None), in item order."""
    if client is None:
        return [function(job, *item) for item in items]
    import distributed
    # The job (paths, JSON text, seeds: a few kB) travels inside each task rather than scattered: data
    # scattered to a worker that is then killed is lost, and every task that needs it is cancelled (seen
    # on a loaded machine, where the cluster's second worker was not up yet when the job was scattered).
    futures = [client.submit(function, job, *item, retries=retries, pure=False) for item in items]
    try:
        with client.as_current():
            distributed.wait(futures, timeout=timeout)
    except (TimeoutError, distributed.TimeoutError) as error:
        done = sum(f.status == "finished" for f in futures)
        client.cancel(futures)
        raise DistributedError("%s: %d of %d tasks finished within %g s (%s)" % (
            describe, done, len(futures), timeout, type(error).__name__)) from None
    results = []
    for item, future in zip(items, futures):
        if future.status != "finished":
            raise DistributedError("%s: task %r failed: %s" % (describe, item, future.exception()))
        results.append(future.result())
    return results


# ---- Monte Carlo ------------------------------------------------------------------------------------------

def _percentiles(values):
    return {"p%d" % p: float(v) for p, v in zip(PERCENTILES, np.percentile(values, PERCENTILES))}


class MonteCarloResult:
    """What :func:`monte_carlo` found: ``metrics`` (N, 3, 5: per draw and run Ra, Rz, RMS, max, mean in m;
    NaN for a failed draw), ``failed`` ({index: message}), ``band_z`` and ``band_norm`` (3 runs x 3
    percentiles x path points, m) and ``time`` of the band's path points, and :meth:`summary`,
    :meth:`to_json`, :meth:`plot`, :meth:`write`."""

    def __init__(self, job, results, time):
        self.samples = len(results)
        self.seed = job["seed"]
        self.use_plant = job["use_plant"]
        self.distribution = job["distribution"]
        self.not_propagated = job.get("not_propagated", [])
        self.metrics = np.full((self.samples, 3, 5), np.nan)
        self.failed = {}
        self.clamped = sum(r["clamped"] for r in results)
        good_z, good_norm = [], []
        for r in results:
            if "error" in r:
                self.failed[r["index"]] = r["error"]
                continue
            self.metrics[r["index"]] = r["metrics"]
            good_z.append(r["z"])
            good_norm.append(r["norm"])
        if not good_z:
            raise DistributedError("monte carlo: every one of the %d draws failed; the first: %s" % (
                self.samples, next(iter(self.failed.values()))))
        self.time = np.asarray(time)[::job["stride"]]
        self.band_z = np.percentile(np.asarray(good_z), PERCENTILES, axis=0).transpose(1, 0, 2)
        self.band_norm = np.percentile(np.asarray(good_norm), PERCENTILES, axis=0).transpose(1, 0, 2)

    def statistics(self):
        """Per run: the percentiles of Ra, Rz, RMS and max (mm), and the max error's 95 % bound."""
        good = self.metrics[~np.isnan(self.metrics[:, 0, 0])] * 1e3
        runs = {}
        for r, key in enumerate(RUN_KEYS):
            runs[key] = {name: _percentiles(good[:, r, m]) for m, name in enumerate(METRIC_NAMES)}
            runs[key]["max_within_mm_95"] = runs[key]["max"]["p95"]
        return runs

    def to_json(self):
        """Everything as a JSON-ready dict (montecarlo.json): statistics, the law, every draw's metrics."""
        return {
            "format": "jointcomp-montecarlo/1",
            "samples": self.samples, "succeeded": self.samples - len(self.failed), "seed": self.seed,
            "simulated_robot": "flexible-joint plant" if self.use_plant else "quasi-static",
            "percentiles": list(PERCENTILES), "units": "mm",
            "runs": self.statistics(),
            "failed": {str(k): v for k, v in sorted(self.failed.items())},
            "stiffness_draws_clamped": self.clamped,
            "distribution": self.distribution,
            "not_propagated": self.not_propagated,
            "per_draw_m": {key: self.metrics[:, r, :4].tolist() for r, key in enumerate(RUN_KEYS)},
        }

    def summary(self):
        """The percentile table and the 95 % bounds as text."""
        stats = self.statistics()
        lines = ["Monte Carlo: %d draws (seed %d, %s robot), %d failed; percentiles 5 / 50 / 95 over the draws, mm"
                 % (self.samples, self.seed, "flexible-joint plant" if self.use_plant else "quasi-static",
                    len(self.failed)),
                 "%-14s %-26s %-26s %-26s %-26s" % ("run", "Ra", "Rz", "RMS 3-D", "max 3-D")]
        for key in RUN_KEYS:
            cells = ["%.4f / %.4f / %.4f" % tuple(stats[key][m]["p%d" % p] for p in PERCENTILES) for m in METRIC_NAMES]
            lines.append("%-14s %-26s %-26s %-26s %-26s" % (key, *cells))
        lines.append("With 95 %% confidence (95 %% of the draws) the compensated path stays within %.4f mm, the "
                     "uncompensated one within %.4f mm (max 3-D error)." % (
                         stats["compensated"]["max_within_mm_95"], stats["uncompensated"]["max_within_mm_95"]))
        if self.not_propagated:
            lines.append("Not propagated: " + "; ".join(self.not_propagated))
        if self.clamped:
            lines.append("%d stiffness draws fell at or below zero and were held at 1 %% of the value" % self.clamped)
        for index, message in sorted(self.failed.items()):
            lines.append("draw %d failed: %s" % (index, message))
        return "\n".join(lines)

    def plot(self, path):
        """The confidence band (5 to 95 %) and the median of the error along the path, uncompensated and
        compensated: Z deviation above, 3-D error norm below."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        figure, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
        for r, colour in ((0, "tab:red"), (2, "tab:blue")):
            label = "without correction" if r == 0 else "stiffness and kinematic correction"
            for axis, band in ((axes[0], self.band_z), (axes[1], self.band_norm)):
                axis.fill_between(self.time, band[r, 0] * 1e3, band[r, 2] * 1e3, color=colour, alpha=0.25,
                                  linewidth=0, label=label + ": 5-95 %")
                axis.plot(self.time, band[r, 1] * 1e3, color=colour, linewidth=0.8, label=label + ": median")
        axes[0].set_ylabel("Z deviation [mm]")
        axes[1].set_ylabel("3-D error [mm]")
        axes[1].set_xlabel("time along the spiral [s]")
        axes[0].set_title("Spiral error under parameter uncertainty: %d draws, seed %d" % (self.samples, self.seed))
        axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, fontsize=8)
        figure.tight_layout()
        _save_figure(figure, path)
        plt.close(figure)

    def write(self, folder):
        """montecarlo.json, montecarlo.csv (one row per draw) and montecarlo_band.png into ``folder``."""
        folder = prepare_output_folder(folder, DistributedError)
        _write_text(folder / "montecarlo.json", json.dumps(self.to_json(), indent=2) + "\n")
        text = io.StringIO()
        writer = csv.writer(text)
        writer.writerow(["draw"] + ["%s_%s_mm" % (k, m) for k in RUN_KEYS for m in METRIC_NAMES] + ["error"])
        for i in range(self.samples):
            writer.writerow([i] + ["%.9g" % (self.metrics[i, r, m] * 1e3) for r in range(3) for m in range(4)]
                            + [self.failed.get(i, "")])
        _write_text(folder / "montecarlo.csv", text.getvalue())
        self.plot(folder / "montecarlo_band.png")


def _write_text(path, text):
    """Whole or not at all, and no temporary left by a kill (jointcomp._paths.write_atomically)."""
    write_atomically(path, lambda stream: stream.write(text.encode("utf-8")))


def _save_figure(figure, path):
    write_atomically(path, lambda stream: figure.savefig(stream, dpi=110, format="png"))


def monte_carlo(urdf, parameters, *, samples=100, seed=DEFAULT_SEED, report=None, distribution=None,
                use_plant=False, client=None, scheduler=None, n_workers=None, serial=False, timeout=3600.0,
                start_timeout=60.0, retries=2, path_points=1500, _kill_marker=None):
    """Monte Carlo of the spiral under parameter uncertainty; returns a :class:`MonteCarloResult`.

    ``urdf``: the robot's URDF path; ``parameters``: its (nominal, identified) parameter file path, or the
    JSON text. The law: ``report`` (a report or its report.json, see :func:`report_distribution`), else
    ``distribution`` (a list of entries or a JSON file, see the module's comments), else the main job's
    perturbation (:func:`main_job_distribution`). ``samples`` draws of ``seed``. ``use_plant``: the
    flexible-joint plant (needs drives; about 2.5 times slower) instead of the quasi-static robot.
    Where: ``client`` (a distributed.Client), ``scheduler`` (an address), a LocalCluster of ``n_workers``
    processes, or ``serial=True`` for this process only (the same results). ``timeout``: seconds for all
    draws; ``retries``: reruns of a task whose worker died or raised.
    """
    if not isinstance(samples, int) or isinstance(samples, bool) or not 1 <= samples <= MAX_SAMPLES:
        raise DistributedError("samples is %r, must be an integer from 1 to %d" % (samples, MAX_SAMPLES))
    if not isinstance(seed, int) or seed < 0:
        raise DistributedError("seed is %r, must be an integer >= 0" % (seed,))
    urdf = _existing(urdf, "urdf")
    parameters_json = _parameters_text(parameters)
    not_propagated = []
    if report is not None:
        entries, not_propagated = report_distribution(report)
    elif distribution is not None:
        entries = (load_distribution(distribution) if isinstance(distribution, (str, os.PathLike))
                   else check_distribution(distribution))
    else:
        entries = main_job_distribution(parameters_json)
        if not entries:
            raise DistributedError("parameters: no effect the main job perturbs (compliance, transmission_error, "
                                   "spring_balancer); give a report or a distribution")
    import jointcomp
    with jointcomp.Robot.from_json(urdf, parameters_json) as nominal:
        if use_plant and not nominal.has_drives:
            raise DistributedError("use_plant: the parameters have no \"plant\" object (drives)")
        time = nominal.spiral_plan().time
    urdf_text = pathlib.Path(urdf).read_text()
    job = {"urdf": urdf, "urdf_text": urdf_text, "parameters_json": parameters_json, "distribution": entries,
           "seed": seed, "use_plant": bool(use_plant), "stride": max(1, -(-len(time) // max(1, path_points))),
           "kill_marker": str(_kill_marker) if _kill_marker else None}
    # Every draw's law is checked here, before any worker starts: a bad name fails now, naming it.
    draw_parameters(parameters_json, urdf_text, entries, seed, 0)
    items = [(i,) for i in range(samples)]
    if serial:
        results = _run_tasks(None, _spiral_task, job, items, timeout, retries, "monte carlo")
    else:
        with cluster(client, scheduler, n_workers, start_timeout) as connected:
            results = _run_tasks(connected, _spiral_task, job, items, timeout, retries, "monte carlo")
    job["not_propagated"] = not_propagated
    return MonteCarloResult(job, results, time)


def _existing(path, name):
    path = pathlib.Path(path)
    if not path.is_file():
        raise DistributedError("%s: %s does not exist or is not a file" % (name, path))
    return str(path.resolve())


def _parameters_text(parameters):
    text = str(parameters)
    if text.lstrip().startswith("{"):
        return text
    return pathlib.Path(_existing(parameters, "parameters")).read_text()


# ---- Fleet ------------------------------------------------------------------------------------------------

class FleetResult:
    """What :func:`fleet` found: ``robots`` (one dict per campaign, in the order given: name, campaign,
    before / after errors in mm, outlier, error), the outlier ``threshold_mm`` and :meth:`summary`,
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
                "outlier_rule": OUTLIER_RULE, "median_after_rms_mm": self.median_mm, "mad_after_rms_mm": self.mad_mm,
                "outlier_threshold_mm": self.threshold_mm,
                "outliers": [r["name"] for r in self.robots if r.get("outlier")],
                "failed": [r["name"] for r in self.failed]}

    def rows(self):
        """(header, rows) of the fleet table (fleet_summary.csv), one row per robot."""
        header = ["robot", "campaign", "before_mean_mm", "before_rms_mm", "before_max_mm", "after_mean_mm",
                  "after_rms_mm", "after_max_mm", "outlier", "error"]
        rows = []
        for r in self.robots:
            b, a = r.get("before", {}), r.get("after", {})
            rows.append([r["name"], r["campaign"]] + ["%.4f" % s[k] if k in s else "" for s in (b, a)
                                                      for k in ("mean_mm", "rms_mm", "max_mm")]
                        + ["yes" if r.get("outlier") else "no", r.get("error", "")])
        return header, rows

    def summary(self):
        """The fleet table as text, outliers and failures flagged, and the outlier rule."""
        header, rows = self.rows()
        lines = ["Fleet %s: %d robots, %d failed; errors of each robot's fitted campaign, mm" % (
            self.method, len(self.robots), len(self.failed)),
            "%-20s %10s %10s %10s %10s  %s" % ("robot", "before RMS", "before max", "after RMS", "after max", "")]
        for r in rows:
            flag = "OUTLIER" if r[8] == "yes" else ("FAILED: " + r[9] if r[9] else "")
            lines.append("%-20s %10s %10s %10s %10s  %s" % (r[0], r[3], r[4], r[6], r[7], flag))
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
                axis.annotate("outlier", (k + 0.2, r["after"]["rms_mm"]), ha="center", va="bottom", color="black",
                              fontsize=8)
        axis.axhline(self.threshold_mm, color="grey", linestyle="--", linewidth=0.8,
                     label="outlier threshold (median + 3 x 1.4826 x MAD)")
        axis.set_xticks(x)
        axis.set_xticklabels([r["name"] for r in good], rotation=45, ha="right", fontsize=8)
        axis.set_ylabel("fitted campaign RMS [mm]")
        axis.set_title("Fleet %s: each robot's error before and after" % self.method)
        axis.legend(fontsize=8)
        figure.tight_layout()
        _save_figure(figure, path)
        plt.close(figure)

    def write(self, folder, details):
        """Each robot's folder (from the tasks' ``details``), the fleet summary files and the plot."""
        folder = pathlib.Path(folder)
        for r, d in zip(self.robots, details):
            if "error" in d:
                continue
            robot_folder = folder / r["name"]
            robot_folder.mkdir(parents=True, exist_ok=True)
            _write_text(robot_folder / "report.json", d["report"])
            _write_text(robot_folder / "summary.txt", d["summary"])
            _write_text(robot_folder / "calibrated.urdf", d["urdf"])
            _write_text(robot_folder / "calibrated.json", d["parameters"])
        header, rows = self.rows()
        text = io.StringIO()
        writer = csv.writer(text)
        writer.writerow(header)
        writer.writerows(rows)
        _write_text(folder / "fleet_summary.csv", text.getvalue())
        _write_text(folder / "fleet_summary.json", json.dumps(self.to_json(), indent=2) + "\n")
        _write_text(folder / "fleet_summary.txt", self.summary() + "\n")
        if any("after" in r for r in self.robots):
            self.plot(folder / "fleet.png")


_FLEET_FILES = ("fleet_summary.csv", "fleet_summary.json", "fleet_summary.txt", "fleet.png")


def fleet(urdf, parameters, campaigns, out, *, method="calibrate", holdouts=None, options=None, client=None,
          scheduler=None, n_workers=None, serial=False, timeout=3600.0, start_timeout=60.0, retries=1):
    """Calibrates (``method="calibrate"``) or runs discovery (``"discover"``) on each campaign file, one robot
    each, starting from the nominal ``urdf`` and ``parameters`` (path or JSON text). ``holdouts``: {campaign:
    [held-out files]} (optional); ``options``: keyword options of jointcomp.calibrate / discover. Writes
    ``out/<robot>/`` (report.json, summary.txt, calibrated.urdf, calibrated.json; the robot is named after
    its campaign file, made a plain file name) and ``out/fleet_summary.{csv,json,txt}`` and ``out/fleet.png``;
    returns a :class:`FleetResult`. ``out`` is checked before any work. A campaign that fails (malformed, not
    identifiable) is reported, not fatal."""
    if method not in ("calibrate", "discover"):
        raise DistributedError("method is %r, must be \"calibrate\" or \"discover\"" % (method,))
    prepare_output_folder(out, DistributedError, "out")
    if isinstance(campaigns, (str, os.PathLike)):
        campaigns = [campaigns]
    campaigns = [str(c) for c in campaigns]
    if not campaigns:
        raise DistributedError("campaigns: none given")
    missing = [c for c in campaigns if not pathlib.Path(c).is_file()]
    holdouts = {str(k): [str(h) for h in v] for k, v in (holdouts or {}).items()}
    missing += [h for v in holdouts.values() for h in v if not pathlib.Path(h).is_file()]
    if missing:
        raise DistributedError("campaign files that do not exist: %s" % ", ".join(missing))
    unknown = [k for k in holdouts if k not in campaigns]
    if unknown:
        raise DistributedError("holdouts: given for campaigns not in the fleet: %s" % ", ".join(unknown))
    job = {"urdf": _existing(urdf, "urdf"), "parameters_json": _parameters_text(parameters), "method": method,
           "options": dict(options or {})}
    items = [(str(pathlib.Path(c).resolve()), [str(pathlib.Path(h).resolve()) for h in holdouts.get(c, [])])
             for c in campaigns]
    if serial:
        details = _run_tasks(None, _fleet_task, job, items, timeout, retries, "fleet")
    else:
        with cluster(client, scheduler, n_workers, start_timeout) as connected:
            details = _run_tasks(connected, _fleet_task, job, items, timeout, retries, "fleet")
    names, robots = set(_FLEET_FILES), []  # a robot's folder never takes the name of a summary file
    for campaign, d in zip(campaigns, details):
        name = base = plain_file_name(pathlib.Path(campaign).stem)
        k = 1
        while name in names:
            k += 1
            name = "%s_%d" % (base, k)
        names.add(name)
        robot = {"name": name, "campaign": campaign}
        for key in ("before", "after", "held_out", "error"):
            if key in d:
                robot[key] = d[key]
        robots.append(robot)
    result = FleetResult(method, robots)
    result.write(out, details)
    return result


# ---- Command line -----------------------------------------------------------------------------------------

def _parser():
    parser = argparse.ArgumentParser(prog="jointcomp", description="Monte Carlo accuracy and fleet calibration "
                                     "on a Dask cluster (jointcomp.distributed)")
    commands = parser.add_subparsers(dest="command", required=True)
    mc = commands.add_parser("montecarlo", help="the spiral's accuracy under parameter uncertainty")
    mc.add_argument("--urdf", required=True)
    mc.add_argument("--params", required=True, help="the nominal (identified) parameter file")
    law = mc.add_mutually_exclusive_group()
    law.add_argument("--report", help="report.json whose standard errors give the law")
    law.add_argument("--distribution", help="JSON file: a list of {parameter, law, scale, relative}")
    mc.add_argument("--samples", type=int, default=100, help="number of draws, 1 to %d" % MAX_SAMPLES)
    mc.add_argument("--seed", type=int, default=DEFAULT_SEED)
    mc.add_argument("--plant", action="store_true", help="simulate the flexible-joint plant (needs drives)")
    mc.add_argument("--out", default="out/montecarlo")
    fl = commands.add_parser("fleet", help="calibrate or discover many robots, one campaign each")
    fl.add_argument("--urdf", required=True)
    fl.add_argument("--params", required=True)
    fl.add_argument("--campaign", action="append", required=True, help="a campaign file (repeat for more)")
    fl.add_argument("--method", choices=("calibrate", "discover"), default="calibrate")
    fl.add_argument("--out", default="out/fleet")
    fl.add_argument("--holdout", action="append", default=[],
                    help="CAMPAIGN=HELD_OUT.csv: a held-out campaign of that robot (repeat for more)")
    for sub in (mc, fl):
        sub.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
        sub.add_argument("--workers", type=int, default=None, help="local worker processes (default: cores)")
        sub.add_argument("--timeout", type=float, default=3600.0, help="seconds for all tasks")
    return parser


def main(argv=None):
    arguments = _parser().parse_args(argv)
    try:
        if arguments.workers is not None and arguments.workers < 1:
            raise DistributedError("--workers is %d, must be at least 1" % arguments.workers)
        if not (math.isfinite(arguments.timeout) and arguments.timeout > 0):  # nan ended in a traceback
            raise DistributedError("--timeout is %r, must be a positive number of seconds" % arguments.timeout)
        prepare_output_folder(arguments.out, DistributedError)
        if arguments.command == "montecarlo":
            result = monte_carlo(arguments.urdf, arguments.params, samples=arguments.samples, seed=arguments.seed,
                                 report=arguments.report, distribution=arguments.distribution,
                                 use_plant=arguments.plant, scheduler=arguments.scheduler,
                                 n_workers=arguments.workers, timeout=arguments.timeout)
            result.write(arguments.out)
            print(result.summary())
            print("wrote %s/montecarlo.{json,csv} and montecarlo_band.png" % arguments.out)
            return 0
        holdouts = {}
        for item in arguments.holdout:
            campaign, separator, held = item.partition("=")
            if not separator or not campaign or not held:
                raise DistributedError("--holdout %r: expected CAMPAIGN=HELD_OUT.csv" % item)
            holdouts.setdefault(campaign, []).append(held)
        result = fleet(arguments.urdf, arguments.params, arguments.campaign, arguments.out, method=arguments.method,
                       holdouts=holdouts, scheduler=arguments.scheduler, n_workers=arguments.workers,
                       timeout=arguments.timeout)
        print(result.summary())
        print("wrote %s/<robot>/ and %s/fleet_summary.{csv,json,txt}, fleet.png" % (arguments.out, arguments.out))
        return 1 if result.failed else 0
    except (DistributedError, JointcompError, OSError) as error:
        print("jointcomp %s: %s" % (arguments.command, error), file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
