"""The paper's spiral prepared once (planned, and compensated with the nominal parameters) and followed by
many truths: the Monte Carlo draw's C call (jc_spiral_job_*)."""

import ctypes
import json

import numpy as np

from . import _native
from ._handle import OwnedHandle
from .errors import InvalidArgumentError


class SpiralJob(OwnedHandle):
    """``SpiralJob(robot, use_plant)``: the spiral planned with ``robot`` and its three runs compensated with
    its parameters, once. :meth:`run` follows them with a truth given as parameter values (``parameters``
    lists their names, nominal values and the main job's perturbation law, from the library). The job keeps
    its own copy of the model; it may be used from several threads at once."""

    @staticmethod
    def _release(handle):
        return _native.lib.jc_spiral_job_free(handle)

    def __init__(self, robot, use_plant=False):
        handle = ctypes.c_void_p()
        _native.check(_native.lib.jc_spiral_job_create(robot.handle, 1 if use_plant else 0, ctypes.byref(handle)))
        self._handle = handle
        self.use_plant = bool(use_plant)
        samples, count = ctypes.c_int32(), ctypes.c_int32()
        _native.check(_native.lib.jc_spiral_job_sizes(self.handle, ctypes.byref(samples), ctypes.byref(count)))
        self.samples = samples.value
        length = ctypes.c_int32()
        _native.check(_native.lib.jc_spiral_job_parameters(self.handle, None, 0, ctypes.byref(length)))
        buffer = ctypes.create_string_buffer(length.value + 1)
        _native.check(_native.lib.jc_spiral_job_parameters(self.handle, buffer, len(buffer), ctypes.byref(length)))
        #: [{"name", "value", "law": {"scale", "relative"} or None}], in the order run() takes the values
        self.parameters = json.loads(buffer.value.decode("utf-8"))
        assert len(self.parameters) == count.value
        self.nominal_values = np.array([p["value"] for p in self.parameters], dtype=np.float64)
        self.index = {p["name"]: k for k, p in enumerate(self.parameters)}

    def time(self):
        """The planned spiral's time (m,), s."""
        time = np.empty(self.samples)
        _native.check(_native.lib.jc_spiral_job_time(self.handle, _native.pointer(time), time.size))
        return time

    def run(self, values, noise_seed, errors=None):
        """Metrics (3 runs x Ra, Rz, RMS, max, mean, m) of the truth whose parameters are ``values`` (as
        ``parameters``), measured with tracker noise ``noise_seed`` (>= 0); ``errors``, when given, a (3, m,
        3) float64 array, receives the measured-minus-planned tool positions."""
        values = np.ascontiguousarray(values, dtype=np.float64)
        if values.shape != self.nominal_values.shape:
            raise InvalidArgumentError("values has shape %s; expected %s" % (values.shape, self.nominal_values.shape))
        metrics = np.empty((3, 5))
        if errors is not None and (errors.shape != (3, self.samples, 3) or errors.dtype != np.float64
                                   or not errors.flags.c_contiguous):
            raise InvalidArgumentError("errors must be a C-contiguous float64 array of shape (3, %d, 3)" % self.samples)
        _native.check(_native.lib.jc_spiral_job_run(
            self.handle, _native.pointer(values), values.size, int(noise_seed), _native.pointer(metrics), metrics.size,
            _native.pointer(errors), 0 if errors is None else errors.size))
        return metrics
