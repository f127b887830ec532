"""Accuracy metrics of tracked paths, as scored in the paper (Olabi et al., ICIT 2012, Table II)."""

import collections
import ctypes

import numpy as np

from . import _native

Metrics = collections.namedtuple("Metrics", "ra rz rms max mean")
Metrics.__doc__ = """Ra (mean |z|) and Rz (max z - min z) of the Z deviations, and RMS, max and mean of the
3-D error norms, all in m."""


def _values(values):
    return np.ascontiguousarray(values, dtype=np.float64).reshape(-1)


def accuracy_metrics(errors):
    """Metrics of error vectors ``errors`` (m, 3), measured minus nominal, in m."""
    errors = _values(errors)
    metrics = np.empty(5)
    _native.check(_native.lib.jc_accuracy_metrics(_native.pointer(errors), errors.size, _native.pointer(metrics),
                                                  metrics.size))
    return Metrics(*metrics.tolist())


def average_absolute_deviation(z):
    """Ra = mean |z_k| of Z deviations ``z`` (m,), in m."""
    z = _values(z)
    ra = ctypes.c_double()
    _native.check(_native.lib.jc_average_absolute_deviation(_native.pointer(z), z.size, ctypes.byref(ra)))
    return ra.value


def peak_to_peak_deviation(z):
    """Rz = max z_k - min z_k of Z deviations ``z`` (m,), in m."""
    z = _values(z)
    rz = ctypes.c_double()
    _native.check(_native.lib.jc_peak_to_peak_deviation(_native.pointer(z), z.size, ctypes.byref(rz)))
    return rz.value
