"""jointcomp: joint-error prediction, offline compensation and the flexible-joint plant of industrial robots.

Python bindings (ctypes and numpy) of the jointcomp C API (libjointcomp.so, header jointcomp/jointcomp.h).
Arrays go in and come out as numpy float64 arrays; units are SI (rad, m, N m, s); a failed call raises a
:class:`JointcompError` subclass carrying the library's message.

Example::

    import jointcomp
    with jointcomp.Robot("rx170.urdf", "rx170.json") as robot:
        result = robot.spiral_experiment()
        for name, metrics in zip(jointcomp.RUN_NAMES, result.metrics):
            print(name, metrics.ra * 1e3, metrics.rz * 1e3)

The library is found as described in :mod:`jointcomp._native` (first of all: the JOINTCOMP_LIBRARY
environment variable).
"""

from . import _native
from .errors import (BusyError, FileError, InternalError, InvalidArgumentError, JointcompError, OutOfMemoryError,
                     PlantLimitError, SolverError, UnreachableError, WrongHandleError)
from .identification import (Report, calibrate, discover, identify_and_compensate, identify_stiffness,
                             identify_transmission_error, simulate_campaign)
from .metrics import Metrics, accuracy_metrics, average_absolute_deviation, peak_to_peak_deviation
from .plant import Plant, PlantStatistics
from .robot import (RUN_NAMES, DynamicCompensation, Robot, SpiralExperiment, SpiralPlan,
                    TrajectoryCompensation)
from .spiral_job import SpiralJob

# jointcomp.distributed (Dask) is imported when first used: `python3 -m jointcomp.distributed` runs it as
# __main__, which an import here would have loaded a second time.
_DISTRIBUTED = ("DistributedError", "FleetResult", "MonteCarloResult", "fleet", "monte_carlo")


def __getattr__(name):
    if name in _DISTRIBUTED:
        from . import distributed
        return getattr(distributed, name)
    raise AttributeError("module 'jointcomp' has no attribute %r" % name)


ABI_VERSION = _native.ABI_VERSION
library_path = _native.library_path


def version():
    """The library's version, "major.minor.patch"."""
    return _native.lib.jc_version().decode("ascii")


__version__ = version()


def abi_version():
    """The binary interface version of the library loaded (equal to ABI_VERSION)."""
    return _native.lib.jc_abi_version()


_progress = None  # the ctypes callback the library holds, kept alive here


def set_progress(callback):
    """``callback(message)`` is told what long calls of this thread (calibrate, discover) are doing, e.g.
    "calibrating: iteration 4, RMS 0.2431 mm per axis"; ``None`` silences them (the default)."""
    global _progress
    if callback is None:
        _progress = None
        _native.check(_native.lib.jc_set_progress_callback(_native.PROGRESS_CALLBACK(), None))
        return
    if not callable(callback):
        raise TypeError("set_progress takes a callable or None")
    _progress = _native.PROGRESS_CALLBACK(lambda message, _: callback(message.decode("utf-8", "replace")))
    _native.check(_native.lib.jc_set_progress_callback(_progress, None))


def status_name(status):
    """The name of a C status code, e.g. "JC_ERROR_SOLVER"."""
    return _native.lib.jc_status_name(status).decode("ascii")


def last_error():
    """The library's message for the last failed call on this thread ("" after a success)."""
    return _native.lib.jc_last_error().decode("utf-8", "replace")


__all__ = [
    "ABI_VERSION", "__version__", "BusyError", "DynamicCompensation", "DistributedError", "FleetResult", "MonteCarloResult", "fleet", "monte_carlo", "FileError", "InternalError", "InvalidArgumentError", "JointcompError", "Metrics",
    "OutOfMemoryError", "Plant", "PlantLimitError", "PlantStatistics", "RUN_NAMES", "Report", "Robot", "SolverError", "SpiralExperiment",
    "SpiralJob", "SpiralPlan", "TrajectoryCompensation", "UnreachableError", "WrongHandleError", "abi_version",
    "accuracy_metrics", "average_absolute_deviation", "calibrate", "discover", "identify_and_compensate",
    "identify_stiffness",
    "identify_transmission_error", "last_error", "library_path", "peak_to_peak_deviation",
    "set_progress", "simulate_campaign", "status_name", "version",
]
