"""Parameter distributions of a Monte Carlo: read, checked, bound to a spiral job's parameters and drawn.

A distribution is a list of entries, each one parameter and its law (plain dicts: they are JSON files too):
  {"parameter": NAME, "law": "normal" | "uniform", "scale": S, "relative": false, "source": "..."}
normal: value + S * N(0, 1); uniform: value + S * U(-1, 1); relative: value * (1 + S * draw). NAME is one of
the robot's parameters as the library names them (jointcomp.SpiralJob(robot).parameters: the effects' own,
unit in the name, "joint_2.stiffness_nm_per_rad", "joint_1.harmonic_output_x2.amplitude_rad", and the
geometry's "joint_3.offset_rad", "joint_3.placement_dx_m", ...), or "joint_J.compliance_rad_per_nm", the
compliance effect's stiffness as a compliance (1 / stiffness), as calibration reports it.
One more kind of entry correlates normal entries (a calibration report gives it from the fit's covariance):
  {"correlation": {"parameters": [NAME, ...], "matrix": [[1, r12, ...], ...]}}
Their standard normal draws are then mixed by a square root of that matrix before their scales apply.

Draw k of seed s (the documented seed scheme): generator = numpy.random.Generator(PCG64(SeedSequence([s,
k]))); one standard normal (normal law) or one uniform(-1, 1) (uniform law) per parameter entry in the
distribution's order; then the tracker's noise seed, generator.integers(0, 2**62). Nothing else draws.
"""

import json
import math
import os
import pathlib

import numpy as np

_DEG = math.pi / 180.0
NOISE_SEED_BOUND = 2 ** 62


class DistributedError(RuntimeError):
    """A Monte Carlo or fleet run that cannot go on: bad input, a cluster that does not start, a timeout."""


def _entry(parameter, law, scale, relative, source):
    return {"parameter": parameter, "law": law, "scale": float(scale), "relative": bool(relative), "source": source}


def main_job_distribution(job):
    """The main job's perturbation of the truth (jc_spiral_experiment's, model/effects/perturbation.cpp), as
    the library states it for each of ``job``'s parameters (a jointcomp.SpiralJob): uniform laws; the
    geometry, which it does not perturb, left out."""
    return [_entry(p["name"], "uniform", p["law"]["scale"], p["law"]["relative"], "main job")
            for p in job.parameters if p["law"] is not None and p["law"]["scale"] > 0.0]


def _read_json_file(path, what):
    path = pathlib.Path(path)
    if not path.is_file():
        raise DistributedError("%s: %s does not exist or is not a file" % (what, path))
    if path.stat().st_size > 64 << 20:
        raise DistributedError("%s: %s is larger than 64 MB" % (what, path))
    try:
        return json.loads(path.read_text(encoding="utf-8-sig"))
    except (ValueError, UnicodeDecodeError) as error:
        raise DistributedError("%s: %s is not JSON: %s" % (what, path, error)) from None


def load_distribution(path):
    """A distribution from a JSON file: a list of entries (see the module's comments), checked."""
    return check_distribution(_read_json_file(path, "distribution"), str(path))


def _finite_scale(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0


def check_distribution(entries, where="distribution"):
    """``entries`` (a list of dicts) checked and completed; DistributedError names the entry at fault. The
    names are checked against the robot's parameters when the law is bound to a job (:func:`bind`)."""
    if not isinstance(entries, list) or not entries:
        raise DistributedError("%s: must be a non-empty list of {parameter, law, scale[, relative]}" % where)
    checked, correlations = [], []
    for k, e in enumerate(entries):
        if isinstance(e, dict) and "correlation" in e:
            correlations.append((k, e["correlation"]))
            continue
        if not isinstance(e, dict) or "parameter" not in e or "scale" not in e:
            raise DistributedError("%s: entry %d needs \"parameter\" and \"scale\": %.200r" % (where, k, e))
        name, law, scale = e["parameter"], e.get("law", "normal"), e["scale"]
        if not isinstance(name, str) or not name:
            raise DistributedError("%s: entry %d: \"parameter\" must be a name, not %.100r" % (where, k, name))
        if law not in ("normal", "uniform"):
            raise DistributedError("%s: entry %d (%s): law %.100r must be \"normal\" or \"uniform\"" % (
                where, k, name, law))
        if not _finite_scale(scale):
            raise DistributedError("%s: entry %d (%s): scale %.100r must be a finite number >= 0" % (
                where, k, name, scale))
        if not isinstance(e.get("relative", False), bool):
            raise DistributedError("%s: entry %d (%s): relative must be true or false" % (where, k, name))
        checked.append(_entry(name, law, scale, e.get("relative", False), str(e.get("source", where))))
    if not checked:
        raise DistributedError("%s: no parameter entry (only correlations)" % where)
    names = [e["parameter"] for e in checked]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DistributedError("%s: parameters listed twice: %s" % (where, ", ".join(twice)))
    for k, correlation in correlations:
        checked.append(_check_correlation(correlation, checked, "%s: entry %d (correlation)" % (where, k)))
    return checked


def _check_correlation(correlation, entries, where):
    """A correlation entry checked, with the matrix's square root (``factor``) the draws are mixed by."""
    if not isinstance(correlation, dict) or "parameters" not in correlation or "matrix" not in correlation:
        raise DistributedError("%s: needs \"parameters\" and \"matrix\"" % where)
    names = correlation["parameters"]
    laws = {e["parameter"]: e["law"] for e in entries if "parameter" in e}
    if (not isinstance(names, list) or len(names) < 2 or not all(isinstance(n, str) for n in names)
            or len(set(names)) != len(names)):
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
        raise DistributedError("%s: \"matrix\" is not a correlation matrix (eigenvalue %.3g)" % (where, values.min()))
    factor = vectors * np.sqrt(np.clip(values, 0.0, None))  # factor @ factor.T == matrix
    return {"correlation": {"parameters": list(names), "matrix": matrix.tolist(), "factor": factor.tolist()}}


def sample_generator(seed, index):
    """Draw ``index``'s own generator: independent of how many draws there are and of who runs them."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), int(index)])))


class BoundLaw:
    """A checked distribution bound to a job's parameters: :meth:`draw` gives draw k's parameter values."""

    def __init__(self, distribution, job):
        self.entries = [e for e in distribution if "parameter" in e]
        position = {e["parameter"]: k for k, e in enumerate(self.entries)}
        self.mixes = [(np.array(c["correlation"]["factor"]), [position[n] for n in c["correlation"]["parameters"]])
                      for c in distribution if "correlation" in c]
        self.nominal = job.nominal_values
        self.normal = np.array([e["law"] == "normal" for e in self.entries])
        self.slots, self.compliance, self.stiffness = [], [], []
        unknown = []
        for e in self.entries:
            name = e["parameter"]
            if name.endswith(".compliance_rad_per_nm"):
                name = name[:-len("compliance_rad_per_nm")] + "stiffness_nm_per_rad"
                self.compliance.append(True)
            else:
                self.compliance.append(False)
            if name not in job.index:
                unknown.append(e["parameter"])
                continue
            self.slots.append(job.index[name])
            self.stiffness.append("stiffness" in name)
        if unknown:
            known = [p["name"] for p in job.parameters]
            raise DistributedError("distribution: %s: not a parameter of this robot (it has %d: %s, ..., %s; and "
                                   "J.compliance_rad_per_nm for a stiffness)" % (
                                       ", ".join(unknown[:5]), len(known), ", ".join(known[:4]), known[-1]))

    def draw(self, seed, index):
        """(values, noise_seed, clamped) of draw ``index``: the truth's parameter values, the tracker's
        seed, and how many stiffnesses fell at or below zero (held at 1 % of their nominal value)."""
        generator = sample_generator(seed, index)
        draws = np.empty(len(self.entries))
        for k, normal in enumerate(self.normal):  # one draw per entry, in the distribution's order
            draws[k] = generator.standard_normal() if normal else generator.uniform(-1.0, 1.0)
        noise_seed = int(generator.integers(0, NOISE_SEED_BOUND))
        for factor, block in self.mixes:
            draws[block] = factor @ draws[block]
        values = self.nominal.copy()
        clamped = 0
        for k, e in enumerate(self.entries):
            slot = self.slots[k]
            value = 1.0 / values[slot] if self.compliance[k] else values[slot]
            moved = value * (1.0 + e["scale"] * draws[k]) if e["relative"] else value + e["scale"] * draws[k]
            if self.compliance[k]:
                moved = 1.0 / moved if moved > 0.0 else -1.0
            if self.stiffness[k] and not moved > 0.0:
                moved, clamped = 0.01 * self.nominal[slot], clamped + 1
            values[slot] = moved
        return values, noise_seed, clamped


def _report_data(report):
    if hasattr(report, "data"):
        return report.data
    if isinstance(report, dict):
        return report
    if isinstance(report, (str, os.PathLike)) and not str(report).lstrip().startswith("{"):
        return _read_json_file(report, "report")
    try:
        return json.loads(report)
    except ValueError as error:
        raise DistributedError("report: the text is not JSON: %s" % error) from None


def _reports_distribution(data):
    """Several identifications of one robot in one document (``jointcomp paper``'s identification/report.json:
    its stiffness and transmission-error reports, and the load effects refitted to the sweep): the union of
    their laws (standard errors only)."""
    entries, left = [], []
    parts = data.get("reports")
    if not isinstance(parts, list):
        raise DistributedError("report: malformed jointcomp-identification-reports/1 report (no list of reports)")
    for part in parts:
        try:
            part_entries, part_left = report_distribution(part)
        except DistributedError as error:
            left.append(str(error))
            continue
        entries += part_entries
        left += part_left
    # The load effects refitted to the sweep (the balancer), by their posterior standard errors.
    for p in (data.get("load_refit") or {}).get("parameters", []):
        if p.get("se"):
            entries.append(_entry(p["name"], "normal", p["se"], False, "load refit to the sweep"))
    if not entries:
        raise DistributedError("report: none of its reports states a parameter with a standard error (%s)"
                               % "; ".join(left))
    return check_distribution(entries, "report"), left


def report_distribution(report):
    """The distribution a report states: ``(entries, not_propagated)``. ``report``: a jointcomp.Report, its
    JSON text or dict, or the path of a report.json. Every estimate with a standard error becomes a normal
    law around the identified value (the parameters must be the identified ones: the report's robot).
    Reports: stiffness and transmission-error identification (also both in one, as ``jointcomp paper``
    writes them), calibration (the instrument frame and target
    are the set-up's, not the robot's: not_propagated) and discovery. A calibration report's correlation
    comes along as a correlation entry over the propagated parameters. A report missing what its format
    promises is named, never a traceback."""
    data = _report_data(report)
    if not isinstance(data, dict):
        raise DistributedError("report: a report is a JSON object, not %s" % type(data).__name__)
    if data.get("format") == "jointcomp-identification-reports/1":
        return _reports_distribution(data)
    try:
        entries, left = _report_entries(data)
        entries = _with_correlation(entries, data.get("correlation"))
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as error:
        raise DistributedError("report: malformed %s report (%s: %.200s)" % (
            data.get("format") or data.get("identification"), type(error).__name__, error)) from None
    if not [e for e in entries if "parameter" in e]:
        raise DistributedError("report: it states no parameter with a standard error that could be propagated"
                               + (" (%s)" % "; ".join(left) if left else ""))
    return check_distribution(entries, "report"), left


def _robot_parameter(name):
    """A report's parameter the robot has (not the measurement set-up's frame, target or scale)."""
    return not (name.startswith(("frame.", "target.", "instrument.", "setup")))


def _report_entries(data):
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
            if _robot_parameter(p["name"]):
                entries.append(_entry(p["name"], "normal", p["sigma"], False, "calibration"))
            else:
                left.append(p["name"] + ": of the measurement set-up, not the robot")
    elif kind == "jointcomp-discovery-report/1":
        for step in data.get("steps", []):
            for p in step.get("parameters", []):
                name, sigma = p["name"], p.get("sigma")
                if sigma and _robot_parameter(name):
                    entries.append(_entry(name, "normal", sigma, False, "discovery step %d" % step["step"]))
                else:
                    left.append(name + ": no standard error, or of the measurement set-up")
    else:
        raise DistributedError("report: %.100r is not a report jointcomp knows (identification, calibration or "
                               "discovery)" % (kind,))
    return entries, left


def _with_correlation(entries, correlation):
    """The entries and, when the report has a correlation, its block over the propagated parameters (a
    principal block of a correlation matrix is one too)."""
    if not correlation:
        return entries
    names = [e["parameter"] for e in entries]
    where = {name: k for k, name in enumerate(correlation["parameters"])}
    kept = [name for name in names if name in where]
    if len(kept) > 1:
        matrix = [[correlation["matrix"][where[a]][where[b]] for b in kept] for a in kept]
        entries = entries + [{"correlation": {"parameters": kept, "matrix": matrix}}]
    return entries
