"""Dynamic compensation through the bindings: a fast move is followed far better than with the static
compensation, on the plant of the same robot; bad shapes and a robot without drives are refused."""

import numpy as np
import pytest

import jointcomp
from conftest import POSTURE


def septic_move(duration=0.8, period=0.004, hold=0.1):
    """Joints 1 to 3 by 0.4, 0.3 and -0.35 rad, rest to rest (position to jerk continuous)."""
    times = np.arange(0.0, duration + 2 * hold + 1e-9, period)
    s = np.clip((times - hold) / duration, 0.0, 1.0)
    shape = s**4 * (35 - 84 * s + 70 * s**2 - 20 * s**3)
    rate = 140 * s**3 * (1 - s) ** 3 / duration
    travel = np.array([0.4, 0.3, -0.35, 0.0, 0.0, 0.0])
    return times, np.array(POSTURE) + np.outer(shape, travel), np.outer(rate, travel)


def run(robot, times, references, velocities):
    plant = jointcomp.Plant(robot)
    plant.reset(references[0], times[0])
    links = np.empty_like(references)
    for k in range(times.size):
        plant.set_reference(references[k], velocities[k])
        links[k] = plant.link_positions()
        if k + 1 < times.size:
            plant.advance(times[k + 1])
    return links


def test_a_fast_move_is_followed(robot):
    times, planned, velocities = septic_move()
    result = robot.compensate_dynamic(times, planned, velocities)
    assert isinstance(result, jointcomp.DynamicCompensation)
    assert result.references.shape == planned.shape and result.reference_velocities.shape == planned.shape
    assert 1 <= result.runs <= 40 and result.max_link_error <= 2e-6
    dynamic = np.max(np.abs(run(robot, times, result.references, result.reference_velocities) - planned))
    static = robot.compensate_trajectory(planned, velocities)
    static_error = np.max(np.abs(run(robot, times, static.references, velocities) - planned))
    assert dynamic < 3e-5, dynamic  # the plant at its default tolerance (1e-6 relative) integrates to about 1e-5 rad
    assert dynamic < 0.02 * static_error, (dynamic, static_error)


def test_bad_inputs_are_refused(robot, bare_robot):
    times, planned, velocities = septic_move(0.2)
    with pytest.raises(jointcomp.InvalidArgumentError, match="plant"):
        bare_robot.compensate_dynamic(times, planned, velocities)
    with pytest.raises(jointcomp.InvalidArgumentError, match="planned has shape"):
        robot.compensate_dynamic(times, planned[:, :5], velocities)
    with pytest.raises(jointcomp.InvalidArgumentError, match="velocities has shape"):
        robot.compensate_dynamic(times, planned, velocities[:-1])
    backwards = times.copy()
    backwards[3] = backwards[2]
    with pytest.raises(jointcomp.InvalidArgumentError, match="increasing"):
        robot.compensate_dynamic(backwards, planned, velocities)
    with pytest.raises(jointcomp.InvalidArgumentError, match="at least 3"):
        robot.compensate_dynamic(times[:2], planned[:2], velocities[:2])
