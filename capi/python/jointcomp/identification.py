"""Identification, calibration and discovery from measurement campaigns (files in jointcomp's campaign format).

Each function leaves the robot it is given unchanged and returns ``(robot, report)``: a new
:class:`jointcomp.Robot` with the identified parameters and a :class:`Report` (the same JSON document the
command-line tool writes as report.json, and a readable summary). Options are keyword arguments, named as
in the C header's ``options_json`` (``jointcomp/jointcomp.h``); a bad one raises
:class:`jointcomp.InvalidArgumentError` naming it.

Example::

    import jointcomp
    with jointcomp.Robot("rx170.urdf", "rx170.json") as robot:
        jointcomp.simulate_campaign(robot, "sweep.csv", protocol="joint2-sweep", seed=3)
        identified, report = jointcomp.identify_transmission_error(robot, "sweep.csv", joint=2, stage=2)
        print(report.summary)
        identified.save(parameters_path="identified.json")
"""

import ctypes
import json
import os

from . import _native
from ._handle import options_json as _options
from .robot import Robot


class Report:
    """The report of an identification, calibration or discovery: ``data`` (the JSON as a dict), ``json``
    (its text) and ``summary`` (readable text)."""

    def __init__(self, handle):
        try:
            self.json = _read_text(_native.lib.jc_report_json, handle)
            self.summary = _read_text(_native.lib.jc_report_summary, handle)
        finally:
            _native.check(_native.lib.jc_report_free(handle))
        self.data = json.loads(self.json)

    def __getitem__(self, key):
        return self.data[key]

    def __repr__(self):
        return "<jointcomp.Report %s>" % self.data.get("format", "?")


def _read_text(function, handle):
    length = ctypes.c_int32()
    _native.check(function(handle, None, 0, ctypes.byref(length)))
    buffer = ctypes.create_string_buffer(length.value + 1)
    _native.check(function(handle, buffer, len(buffer), ctypes.byref(length)))
    return buffer.value.decode("utf-8")


def _paths(paths, name):
    """One path or a sequence of paths as the newline-separated list the C API takes."""
    if paths is None:
        return None
    if isinstance(paths, (str, bytes, os.PathLike)):
        paths = [paths]
    items = [os.fsdecode(p) for p in paths]
    for item in items:
        if "\n" in item:
            raise ValueError("%s: a path may not contain a newline: %r" % (name, item))
    return "\n".join(items).encode("utf-8")


def _run(function, *arguments):
    robot = ctypes.c_void_p()
    report = ctypes.c_void_p()
    _native.check(function(*arguments, ctypes.byref(robot), ctypes.byref(report)))
    # Both handles are ours from here: wrap the robot first so that it is freed even if the report fails.
    result = Robot._adopt(robot)
    return result, Report(report)


def simulate_campaign(truth, campaign_path, *, protocol, **options):
    """Simulates a measurement campaign with ``truth`` (a Robot) as the real robot and writes it to
    ``campaign_path``. ``protocol``: "stiffness", "joint-sweep", "joint2-sweep", "back-and-forth", "spiral"
    or "random"; options: seed, noise, plant, joint (1-based), from_deg, to_deg, step_deg, settle_s, cycles,
    count, pose_deg, warm_up ([rise_degc, time_constant_s, start_degc]). Returns ``campaign_path``."""
    options["protocol"] = protocol
    _native.check(_native.lib.jc_simulate_campaign(truth.handle, _options(options),
                                                   _native.text(campaign_path, "campaign_path")))
    return campaign_path


def identify_stiffness(nominal, campaign_path, *, method="local"):
    """Joint stiffness from a stiffness campaign; the robot returned carries the ``method``'s estimates
    ("local" or "global")."""
    return _run(_native.lib.jc_identify_stiffness, nominal.handle, _native.text(campaign_path, "campaign_path"),
                _options({"method": method}))


def identify_transmission_error(nominal, campaign_path, **options):
    """Harmonics of one joint's transmission error from a sweep of that joint. Options: joint (1-based,
    default 2), stage (1 = motor, ..., stages + 1 = output; default 2), orders (candidate orders)."""
    return _run(_native.lib.jc_identify_transmission_error, nominal.handle,
                _native.text(campaign_path, "campaign_path"), _options(options))


def calibrate(nominal, campaigns, holdouts=None, **options):
    """Kinematic calibration on ``campaigns`` (one path or several: campaigns from different instrument
    set-ups each get their own frame), checked on ``holdouts`` (paths; their instrument frame re-fitted).
    Options: loss ("huber", "cauchy", "none"), loss_scale_mm, pivot_threshold, fixed (names), and the
    geometry limits max_offset_deg, max_placement_shift_mm, max_placement_turn_deg (a fit beyond is refused)."""
    if campaigns is None:
        raise TypeError("campaigns: a path or a sequence of paths is needed, not None")
    return _run(_native.lib.jc_calibrate, nominal.handle, _paths(campaigns, "campaigns"),
                _paths(holdouts, "holdouts"), _options(options))


def discover(nominal, campaigns, holdouts=None, **options):
    """Residual discovery on ``campaigns`` (one path or several), judged on ``holdouts``. Options: base
    ("textbook", the default, or "frame"), max_steps, max_harmonic_order, folds, min_cv_gain, noise_floor_mm,
    types, loss, table_knots, max_prior_weight, max_ridge_weight, transfer_significance, min_group_share,
    angle_ranges, pairs (jc_discover in jointcomp.h)."""
    return _run(_native.lib.jc_discover, nominal.handle, _paths(campaigns, "campaigns"),
                _paths(holdouts, "holdouts"), _options(options))


def identify_and_compensate(nominal, truth, *, seed=2012, use_plant=False, dynamic_correction=False,
                            feed_rate_m_per_s=0.03):
    """The paper's whole method on ``truth`` (a Robot playing the real robot; jc_identify_and_compensate):
    its identification campaigns simulated on ``truth`` with the instruments' noise of ``seed``, the joint
    stiffnesses and joint 2's transmission error identified against ``nominal``'s parameters, and the spiral
    compensated with the identified model and followed by ``truth`` (quasi-static, or the flexible-joint plant
    with ``use_plant``; ``dynamic_correction`` adds the fourth run). Returns ``(identified, metrics, report)``:
    the identified Robot, one :class:`jointcomp.Metrics` per run (see jointcomp.RUN_NAMES; the fourth is the
    dynamic correction's) and the :class:`Report` holding both identifications' reports."""
    from .metrics import Metrics
    import numpy as np
    for name, robot in (("nominal", nominal), ("truth", truth)):
        if not isinstance(robot, Robot):
            raise TypeError("%s must be a jointcomp.Robot, not %s" % (name, type(robot).__name__))
    metrics = np.empty((4 if dynamic_correction else 3, 5))
    robot = ctypes.c_void_p()
    report = ctypes.c_void_p()
    options = {"seed": seed, "use_plant": use_plant, "dynamic_correction": dynamic_correction,
               "feed_rate_m_per_s": feed_rate_m_per_s}
    _native.check(_native.lib.jc_identify_and_compensate(nominal.handle, truth.handle, _options(options),
                                                         _native.pointer(metrics), metrics.size,
                                                         ctypes.byref(robot), ctypes.byref(report)))
    identified = Robot._adopt(robot)
    return identified, [Metrics(*row) for row in metrics.tolist()], Report(report)
