"""Closing a handle while a call uses it (another thread's, or the call whose progress callback is running)
is refused with BusyError and leaves the object usable; it never frees memory a call still reads."""

import threading

import numpy as np
import pytest

import jointcomp
from conftest import RX170_PARAMETERS, RX170_URDF


def test_close_inside_and_during_calibration_is_refused(tmp_path):
    robot = jointcomp.Robot(RX170_URDF, RX170_PARAMETERS)
    campaign = jointcomp.simulate_campaign(robot, tmp_path / "fit.csv", protocol="random", seed=5, count=60)
    inside, may_leave = threading.Event(), threading.Event()
    seen = {}

    def progress(message):
        if inside.is_set():
            return
        with pytest.raises(jointcomp.BusyError, match="on this thread") as own:
            robot.close()  # from the callback of the call that uses the robot
        seen["own"] = own.value
        inside.set()
        may_leave.wait(timeout=60)

    def calibrate():
        jointcomp.set_progress(progress)
        try:
            calibrated, report = jointcomp.calibrate(robot, campaign)
            seen["result"] = (calibrated.dof, report)
            calibrated.close()
        finally:
            jointcomp.set_progress(None)

    thread = threading.Thread(target=calibrate)
    thread.start()
    assert inside.wait(timeout=60)
    with pytest.raises(jointcomp.BusyError, match="on other threads"):
        robot.close()
    assert robot.dof == 6  # still open: the refused close changed nothing
    may_leave.set()
    thread.join()
    assert "own" in seen and seen["result"][0] == 6
    robot.close()  # idle now
    with pytest.raises(jointcomp.InvalidArgumentError, match="closed"):
        robot.forward_kinematics(np.zeros(6))


def test_close_during_compensate_trajectory_never_crashes():
    robot = jointcomp.Robot(RX170_URDF, RX170_PARAMETERS)
    plan = robot.spiral_plan()
    outcomes = []
    started = threading.Event()

    def compensate():
        for _ in range(20):
            started.set()
            try:
                robot.compensate_trajectory(plan.q, plan.qd)
                outcomes.append("ok")
            except (jointcomp.InvalidArgumentError, jointcomp.WrongHandleError) as error:
                outcomes.append("closed")  # the handle was freed between two calls
                assert "closed" in str(error) or "already freed" in str(error)
                return

    thread = threading.Thread(target=compensate)
    thread.start()
    started.wait(timeout=60)
    refused = 0
    while True:
        try:
            robot.close()
            break
        except jointcomp.BusyError:
            refused += 1
    thread.join()
    assert outcomes and set(outcomes) <= {"ok", "closed"}
    assert outcomes.count("closed") <= 1 and ("closed" not in outcomes or outcomes[-1] == "closed")
