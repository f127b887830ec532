"""Two robots in two Python threads (ctypes releases the GIL) give the results of one after the other."""

import threading

import numpy as np

import jointcomp
from conftest import POSTURE, RX170_PARAMETERS, RX170_URDF


def work(robot):
    plan = robot.spiral_plan()
    references = robot.compensate_trajectory(plan.q, plan.qd).references
    kinematics = [robot.forward_kinematics(np.array(POSTURE) + 0.01 * k) for k in range(20)]
    metrics = robot.spiral_experiment(use_plant=False).metrics
    return references, kinematics, metrics


def same(a, b):
    return (np.array_equal(a[0], b[0]) and all(np.array_equal(x, y) for x, y in zip(a[1], b[1]))
            and a[2] == b[2])


def test_two_handles_in_two_threads():
    robots = [jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) for _ in range(2)]
    sequential = [work(robot) for robot in robots]
    results = [None, None]

    def run(index):
        results[index] = work(robots[index])

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for robot in robots:
        robot.close()
    assert same(sequential[0], sequential[1])
    assert same(results[0], sequential[0]) and same(results[1], sequential[0])
