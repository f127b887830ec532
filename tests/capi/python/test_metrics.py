"""Accuracy metrics: Ra, Rz, RMS, max and mean, and their errors."""

import ctypes
import math

import numpy as np
import pytest

import jointcomp


def test_metrics_of_known_errors():
    errors = np.array([[0.001, 0.0, 0.002], [0.0, 0.0, -0.002], [0.0, 0.003, 0.001]])
    metrics = jointcomp.accuracy_metrics(errors)
    assert metrics.ra == pytest.approx(0.005 / 3, abs=1e-15)
    assert metrics.rz == pytest.approx(0.004, abs=1e-15)
    norms = np.linalg.norm(errors, axis=1)
    assert metrics.rms == pytest.approx(math.sqrt(np.mean(norms ** 2)), abs=1e-15)
    assert metrics.max == pytest.approx(norms.max(), abs=1e-15)
    assert metrics.mean == pytest.approx(norms.mean(), abs=1e-15)
    assert jointcomp.average_absolute_deviation(errors[:, 2]) == metrics.ra
    assert jointcomp.peak_to_peak_deviation(errors[:, 2]) == metrics.rz


def test_metric_errors():
    with pytest.raises(jointcomp.InvalidArgumentError, match="multiple of 3"):
        jointcomp.accuracy_metrics(np.zeros(4))
    with pytest.raises(jointcomp.InvalidArgumentError, match="multiple of 3"):
        jointcomp.accuracy_metrics(np.zeros((0, 3)))
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"errors\[4\] is NaN"):
        jointcomp.accuracy_metrics([[0, 0, 0], [0, np.nan, 0]])
    with pytest.raises(jointcomp.InvalidArgumentError, match="z_len is 0"):
        jointcomp.peak_to_peak_deviation([])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"z\[1\] is \+infinity"):
        jointcomp.average_absolute_deviation([0.0, np.inf])


def test_sizes_beyond_32_bits_are_refused_not_wrapped(tmp_path):
    # ctypes wrapped 2^32 + 1 into 1: Ra of 2^32 + 1 values was |z_0| (1.0 where the truth was 2.3e-10).
    from jointcomp import _native
    z = np.array([1.0, 0.0])
    ra = ctypes.c_double()
    with pytest.raises(ctypes.ArgumentError, match="4294967297 is beyond the library's 32-bit sizes"):
        _native.lib.jc_average_absolute_deviation(_native.pointer(z), 2**32 + 1, ctypes.byref(ra))
    with pytest.raises(ctypes.ArgumentError, match="-2147483649 is beyond"):
        _native.lib.jc_peak_to_peak_deviation(_native.pointer(z), -2**31 - 1, ctypes.byref(ra))
    _native.check(_native.lib.jc_average_absolute_deviation(_native.pointer(z), np.int64(2), ctypes.byref(ra)))
    assert ra.value == 0.5
    # The same through the public functions, on 2^32 + 1 values that take no memory (a sparse file): refused
    # before a value is read.
    try:
        huge = np.memmap(tmp_path / "huge.bin", dtype=np.float64, mode="w+", shape=(2**32 + 1,))
    except (OSError, ValueError) as error:
        pytest.skip("no sparse file of 32 GiB here: %s" % error)
    huge[0] = 1.0
    for function in (jointcomp.average_absolute_deviation, jointcomp.peak_to_peak_deviation):
        with pytest.raises(ctypes.ArgumentError, match="4294967297 is beyond"):
            function(huge)
