"""Shared fixtures of the binding tests: the shipped RX170 (with and without drives) and the UR10."""

import pathlib

import pytest

import jointcomp

CHECKOUT = pathlib.Path(__file__).resolve().parents[3]
RX170_URDF = CHECKOUT / "model" / "robots" / "rx170.urdf"
RX170_PARAMETERS = CHECKOUT / "model" / "params" / "rx170.json"
UR10_URDF = CHECKOUT / "model" / "robots" / "ur10.urdf"
HEADER = CHECKOUT / "capi" / "include" / "jointcomp" / "jointcomp.h"
MINIMAL_PARAMETERS = '{"format": "jointcomp-parameters/1", "robot": "rx170", "effects": []}'
DEG = 3.141592653589793 / 180.0
# A posture in front of the robot, away from singularities and limits.
POSTURE = [10 * DEG, 60 * DEG, 70 * DEG, 5 * DEG, 40 * DEG, 15 * DEG]


@pytest.fixture
def robot():
    with jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as loaded:
        yield loaded


@pytest.fixture
def bare_robot():
    """The RX170 without joint errors and without drives."""
    with jointcomp.Robot.from_json(RX170_URDF, MINIMAL_PARAMETERS) as loaded:
        yield loaded


@pytest.fixture
def plant(robot):
    with robot.plant() as created:
        yield created
