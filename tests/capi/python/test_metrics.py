"""Accuracy metrics: Ra, Rz, RMS, max and mean, and their errors."""

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
