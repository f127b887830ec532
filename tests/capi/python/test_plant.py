"""Plant: creation, inputs, stepping, outputs, state, statistics, snapshots and their errors."""

import numpy as np
import pytest

import jointcomp
from conftest import POSTURE

VELOCITY = np.array([0.02, -0.01, 0.01, 0, 0, 0])


def drive(plant, start, periods, period=0.004):
    """Feeds a ramp from `start` at VELOCITY for `periods` controller periods."""
    t0 = plant.time
    for k in range(1, periods + 1):
        plant.set_reference(start + VELOCITY * (k * period), VELOCITY)
        plant.advance(t0 + k * period)


def test_needs_drives(bare_robot):
    with pytest.raises(jointcomp.InvalidArgumentError, match="no \"plant\" object"):
        jointcomp.Plant(bare_robot)


def test_rest_stepping_and_outputs(plant):
    assert plant.dof == 6
    plant.reset(POSTURE, 1.0)
    assert plant.time == 1.0
    np.testing.assert_array_equal(plant.motor_positions(), POSTURE)
    sag = plant.link_positions() - POSTURE
    assert 1e-6 < np.max(np.abs(sag)) < 1e-2
    np.testing.assert_array_equal(plant.link_velocities(), np.zeros(6))
    np.testing.assert_array_equal(plant.motor_velocities(), np.zeros(6))
    drive(plant, np.array(POSTURE), 5)
    assert plant.time == pytest.approx(1.02, abs=1e-12)
    assert plant.link_velocities()[0] > 0
    assert abs(plant.motor_torques()[1]) > 10
    state = plant.state()
    assert state.shape == (30,)
    np.testing.assert_array_equal(state[:6], plant.link_positions())
    np.testing.assert_array_equal(state[18:24], plant.motor_velocities())
    statistics = plant.statistics()
    assert statistics.steps > 0 and statistics.rhs_evaluations >= statistics.steps


def test_snapshots_continue_exactly(plant):
    plant.reset(POSTURE)
    drive(plant, np.array(POSTURE), 3)
    snapshot = plant.save()
    assert snapshot.shape == (plant.snapshot_size,) == (10 * 6 + 14,)
    plant.set_tool_wrench([0, 0, -50, 0, 0, 0])
    plant.set_payload(5.0, [0, 0, 0.05])
    plant.advance(plant.time + 0.02)
    continued = plant.link_positions()
    plant.reset(POSTURE)
    plant.restore(snapshot)
    plant.set_tool_wrench([0, 0, -50, 0, 0, 0])
    plant.set_payload(5.0, [0, 0, 0.05])
    plant.advance(plant.time + 0.02)
    np.testing.assert_array_equal(plant.link_positions(), continued)
    with pytest.raises(jointcomp.InvalidArgumentError, match="snapshot_len"):
        plant.restore(snapshot[:-1])
    bad = snapshot.copy()
    bad[0] = 99
    with pytest.raises(jointcomp.InvalidArgumentError, match="format"):
        plant.restore(bad)
    bad = snapshot.copy()
    bad[1] = 7
    with pytest.raises(jointcomp.InvalidArgumentError, match="another number of joints"):
        plant.restore(bad)


def test_input_errors(plant):
    plant.reset(POSTURE)
    with pytest.raises(jointcomp.InvalidArgumentError, match="not after"):
        plant.advance(0.0)
    with pytest.raises(jointcomp.InvalidArgumentError, match="end_time is NaN"):
        plant.advance(float("nan"))
    with pytest.raises(jointcomp.InvalidArgumentError, match="start_time is"):
        plant.reset(POSTURE, float("inf"))
    with pytest.raises(jointcomp.InvalidArgumentError, match="velocity_len is 2"):
        plant.set_reference(POSTURE, [0, 0])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"position\[0\] is NaN"):
        plant.set_reference([np.nan] * 6, np.zeros(6))
    with pytest.raises(jointcomp.InvalidArgumentError, match="wrench_len is 5"):
        plant.set_tool_wrench(np.zeros(5))
    with pytest.raises(jointcomp.InvalidArgumentError, match="mass is negative"):
        plant.set_payload(-1.0, [0, 0, 0])


def test_watchdog_stops_a_runaway(plant):
    """A 0.5 rad step of joint 1 is beyond the drive's tracking envelope: PlantLimitError naming the joint,
    then no advance until reset; a wider envelope lets the step through."""
    target = np.array(POSTURE)
    target[0] -= 0.5
    plant.reset(POSTURE, 0.0)
    plant.set_reference(target, np.zeros(6))
    with pytest.raises(jointcomp.PlantLimitError, match="joint_1 has a following error"):
        plant.advance(0.004)
    with pytest.raises(jointcomp.PlantLimitError, match="reset the plant"):
        plant.advance(0.008)
    with pytest.raises(jointcomp.InvalidArgumentError, match="tracking_envelope_rad"):
        plant.set_watchdog(-1.0)
    plant.set_watchdog(tracking_envelope_rad=1.0)
    plant.reset(POSTURE, 0.0)
    plant.set_reference(target, np.zeros(6))
    plant.advance(0.1)
    assert plant.time == pytest.approx(0.1)


def test_the_plant_outlives_its_robot(robot):
    plant = robot.plant()
    robot.close()
    plant.reset(POSTURE)
    drive(plant, np.array(POSTURE), 2)
    assert np.all(np.isfinite(plant.link_positions()))
    plant.close()
    with pytest.raises(jointcomp.InvalidArgumentError, match="closed"):
        plant.advance(1.0)


def test_integrator_options_reach_the_plant(robot):
    """Keyword options by PlantOptions' names: stepping past 1 ms updates takes fewer CVODE steps and ends within
    microradians of the plant that stops at each; an unknown name or a value out of range raises, naming it."""
    stopping, past = robot.plant(), robot.plant(step_past_updates_s=np.float64(0.01), max_order=np.int64(3))
    for plant in (stopping, past):
        plant.reset(POSTURE)
        drive(plant, np.array(POSTURE), 400, period=0.001)
    assert past.statistics().steps < stopping.statistics().steps
    np.testing.assert_allclose(past.link_positions(), stopping.link_positions(), rtol=0, atol=5e-6)
    assert not np.array_equal(past.link_positions(), stopping.link_positions())
    with pytest.raises(jointcomp.InvalidArgumentError, match="step_past"):
        robot.plant(step_past=0.01)
    with pytest.raises(jointcomp.InvalidArgumentError, match="max_order"):
        robot.plant(max_order=9)
