"""Robot: loading and its errors, queries, conditions, kinematics and gravity, wrong and closed handles."""

import ctypes
import json

import numpy as np
import pytest

import jointcomp
from jointcomp import _native
from conftest import MINIMAL_PARAMETERS, POSTURE, RX170_PARAMETERS, RX170_URDF, UR10_URDF


def test_loading_errors(tmp_path):
    with pytest.raises(jointcomp.FileError, match="nonexistent"):
        jointcomp.Robot(tmp_path / "nonexistent.urdf")
    with pytest.raises(jointcomp.FileError, match="nonexistent.json"):
        jointcomp.Robot(RX170_URDF, tmp_path / "nonexistent.json")
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "jointcomp-parameters/1", "robot": ')
    with pytest.raises(jointcomp.FileError, match="broken.json"):
        jointcomp.Robot(RX170_URDF, broken)
    with pytest.raises(jointcomp.FileError, match="rx160"):
        jointcomp.Robot.from_json(RX170_URDF, MINIMAL_PARAMETERS.replace("rx170", "rx160"))
    with pytest.raises(jointcomp.InvalidArgumentError, match="parameters_json is NULL|urdf_path is NULL"):
        jointcomp.Robot(None, parameters_json=MINIMAL_PARAMETERS)
    with pytest.raises(ValueError, match="not both"):
        jointcomp.Robot(RX170_URDF, RX170_PARAMETERS, parameters_json=MINIMAL_PARAMETERS)
    with pytest.raises(TypeError):
        jointcomp.Robot(42)


def test_queries(robot, bare_robot):
    assert robot.dof == 6
    assert robot.name == "rx170"
    assert repr(robot) == "<jointcomp.Robot 'rx170', 6 joints>"
    lower, upper = robot.joint_limits()
    assert lower.shape == upper.shape == (6,)
    assert np.all(lower < upper)
    assert robot.has_drives
    assert not bare_robot.has_drives
    parameters = json.loads(robot.parameters_json())
    assert parameters["robot"] == "rx170" and "plant" in parameters
    # The parameters written out load back into an equal model.
    with jointcomp.Robot.from_json(RX170_URDF, robot.parameters_json()) as reloaded:
        assert reloaded.has_drives
        np.testing.assert_allclose(reloaded.predict_joint_errors(POSTURE), robot.predict_joint_errors(POSTURE),
                                   rtol=0, atol=1e-12)


def test_forward_and_inverse_kinematics(robot):
    pose = robot.forward_kinematics(POSTURE)
    assert pose.shape == (4, 4)
    np.testing.assert_array_equal(pose[3], [0, 0, 0, 1])
    q, singular = robot.inverse_kinematics(pose, POSTURE)
    assert not singular
    np.testing.assert_allclose(q, POSTURE, atol=1e-9)
    solutions = robot.inverse_kinematics_all(pose, POSTURE)
    assert 2 <= len(solutions) <= 8 and solutions.shape[1] == 6
    for solution in solutions:
        np.testing.assert_allclose(robot.forward_kinematics(solution), pose, atol=1e-9)
    far = pose.copy()
    far[0, 3] = 10.0
    with pytest.raises(jointcomp.UnreachableError, match="^jc_inverse_kinematics"):
        robot.inverse_kinematics(far, POSTURE)
    skewed = pose.copy()
    skewed[0, 0] *= 1.1
    with pytest.raises(jointcomp.InvalidArgumentError, match="not a rotation"):
        robot.inverse_kinematics(skewed, POSTURE)
    with pytest.raises(jointcomp.InvalidArgumentError, match="pose_len is 12"):
        robot.inverse_kinematics(pose[:3], POSTURE)
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"q has shape \(5,\)"):
        robot.forward_kinematics(POSTURE[:5])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"q\[1\] is NaN"):
        robot.forward_kinematics([0, np.nan, 0, 0, 0, 0])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"seed\[0\] is \+infinity"):
        robot.inverse_kinematics(pose, [np.inf, 0, 0, 0, 0, 0])


def test_inverse_kinematics_all_needs_a_closed_form():
    with jointcomp.Robot(UR10_URDF) as ur10:
        pose = ur10.forward_kinematics([0.1, -1.0, 1.2, -0.5, 1.0, 0.3])
        with pytest.raises(jointcomp.InvalidArgumentError, match="^jc_inverse_kinematics_all"):
            ur10.inverse_kinematics_all(pose, np.zeros(6))
        # Damped least squares from a nearby seed still works.
        q, _ = ur10.inverse_kinematics(pose, [0.15, -0.95, 1.15, -0.45, 1.05, 0.25])
        np.testing.assert_allclose(ur10.forward_kinematics(q), pose, atol=1e-9)


def test_jacobian_is_the_derivative_of_the_tool_position(robot):
    jacobian = robot.jacobian(POSTURE)
    assert jacobian.shape == (6, 6)
    step = 1e-7
    for j in range(6):
        plus, minus = np.array(POSTURE), np.array(POSTURE)
        plus[j] += step
        minus[j] -= step
        derivative = (robot.forward_kinematics(plus)[:3, 3] - robot.forward_kinematics(minus)[:3, 3]) / (2 * step)
        np.testing.assert_allclose(jacobian[:3, j], derivative, atol=1e-6)
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"q has shape \(7,\)"):
        robot.jacobian(np.zeros(7))


def test_gravity_is_the_gradient_of_the_potential_energy(robot):
    # Gravity torques do no work along a virtual displacement that keeps the centres of mass level: check
    # instead that they change sign with the arm's lean, and stay finite.
    tau = robot.gravity_torques(POSTURE)
    assert tau.shape == (6,) and np.all(np.isfinite(tau)) and abs(tau[1]) > 100.0
    leaning_back = np.array(POSTURE)
    leaning_back[1] = -POSTURE[1]
    leaning_back[2] = -POSTURE[2]
    assert np.sign(robot.gravity_torques(leaning_back)[1]) != np.sign(tau[1])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"q\[0\] is -infinity"):
        robot.gravity_torques([-np.inf, 0, 0, 0, 0, 0])


def test_conditions_change_the_errors(robot):
    free = robot.predict_joint_errors(POSTURE)
    robot.set_payload(20.0, [0, 0, 0.1])
    loaded = robot.predict_joint_errors(POSTURE)
    assert abs(loaded[1] - free[1]) > 1e-6
    robot.set_payload(0.0, [0, 0, 0.1])
    robot.set_tool_wrench([0, 0, -200, 0, 0, 0])
    pushed = robot.predict_joint_errors(POSTURE)
    assert abs(pushed[1] - free[1]) > 1e-6
    robot.set_tool_wrench(np.zeros(6))
    np.testing.assert_array_equal(robot.predict_joint_errors(POSTURE), free)
    with pytest.raises(jointcomp.InvalidArgumentError, match="mass is negative"):
        robot.set_payload(-1.0, [0, 0, 0])
    with pytest.raises(jointcomp.InvalidArgumentError, match="com_len is 2"):
        robot.set_payload(1.0, [0, 0])
    with pytest.raises(jointcomp.InvalidArgumentError, match="wrench_len is 3"):
        robot.set_tool_wrench([0, 0, 1])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"wrench\[2\] is NaN"):
        robot.set_tool_wrench([0, 0, np.nan, 0, 0, 0])


def test_closed_and_wrong_handles(robot, plant):
    int32 = ctypes.c_int32()
    with pytest.raises(jointcomp.WrongHandleError, match="expected a jc_robot, got a jc_plant"):
        _native.check(_native.lib.jc_robot_dof(plant.handle, ctypes.byref(int32)))
    with pytest.raises(jointcomp.WrongHandleError, match="expected a jc_plant, got a jc_robot"):
        _native.check(_native.lib.jc_plant_dof(robot.handle, ctypes.byref(int32)))
    not_a_handle = (ctypes.c_uint64 * 8)()
    with pytest.raises(jointcomp.WrongHandleError, match="not a live jointcomp handle"):
        _native.check(_native.lib.jc_robot_dof(ctypes.cast(not_a_handle, ctypes.c_void_p), ctypes.byref(int32)))
    other = jointcomp.Robot(RX170_URDF)
    other.close()
    other.close()  # closing twice is harmless
    with pytest.raises(jointcomp.InvalidArgumentError, match="closed"):
        other.forward_kinematics(POSTURE)
    assert repr(other) == "<jointcomp.Robot (closed)>"


def test_batches_equal_the_rows_one_by_one(robot):
    """FK, Jacobian, gravity, joint errors and compensation of an (m, n) batch: row k equals the call on
    row k alone, and the shapes are (m, ...)."""
    rng = np.random.default_rng(5)
    lower, upper = robot.joint_limits()
    batch = lower + (upper - lower) * (0.3 + 0.4 * rng.random((4, robot.dof)))
    poses = robot.forward_kinematics(batch)
    jacobians = robot.jacobian(batch)
    gravity = robot.gravity_torques(batch)
    errors = robot.predict_joint_errors(batch)
    references, iterations = robot.compensate(batch)
    assert poses.shape == (4, 4, 4) and jacobians.shape == (4, 6, robot.dof)
    assert gravity.shape == errors.shape == references.shape == (4, robot.dof) and iterations.shape == (4,)
    for k, q in enumerate(batch):
        np.testing.assert_array_equal(poses[k], robot.forward_kinematics(q))
        np.testing.assert_array_equal(jacobians[k], robot.jacobian(q))
        np.testing.assert_array_equal(gravity[k], robot.gravity_torques(q))
        np.testing.assert_array_equal(errors[k], robot.predict_joint_errors(q))
        reference, count = robot.compensate(q)
        np.testing.assert_array_equal(references[k], reference)
        assert iterations[k] == count
    # Velocities go row with row.
    velocities = 0.1 * np.ones_like(batch)
    np.testing.assert_array_equal(robot.predict_joint_errors(batch, velocities)[2],
                                  robot.predict_joint_errors(batch[2], velocities[2]))


def test_wrong_shapes_are_errors_not_reinterpreted(robot):
    n = robot.dof
    flat = np.zeros(3 * n)  # three rows' worth of numbers in one flat array
    for call in (robot.forward_kinematics, robot.jacobian, robot.gravity_torques, robot.predict_joint_errors,
                 robot.compensate):
        with pytest.raises(jointcomp.InvalidArgumentError, match=r"has shape \(%d,\)" % (3 * n)):
            call(flat)
        with pytest.raises(jointcomp.InvalidArgumentError, match="expected"):
            call(np.zeros((2, n + 1)))
        with pytest.raises(jointcomp.InvalidArgumentError):
            call(np.zeros((2, 2, n)))
    with pytest.raises(jointcomp.InvalidArgumentError, match="expected \\(m, %d\\)" % n):
        robot.compensate_trajectory(flat)
    with pytest.raises(jointcomp.InvalidArgumentError, match="velocities has shape"):
        robot.compensate_trajectory(np.zeros((3, n)), velocities=np.zeros((2, n)))
    with pytest.raises(jointcomp.InvalidArgumentError, match="velocity has shape"):
        robot.predict_joint_errors(np.zeros((3, n)), np.zeros((2, n)))


def test_version_attribute():
    assert jointcomp.__version__ == jointcomp.version()


def test_chain_choice_on_a_ros_industrial_urdf():
    """A ROS-Industrial layout (base, flange, tool0, a camera on link_3) loads to tool0 by default; tip_link
    and base_link choose another chain; an unknown link is a FileError naming it."""
    from conftest import CHECKOUT
    urdf = CHECKOUT / "tests" / "data" / "urdf" / "ur10_ros_industrial.urdf"
    with jointcomp.Robot(urdf) as arm, jointcomp.Robot(UR10_URDF) as plain, \
            jointcomp.Robot(urdf, tip_link="flange") as at_flange, \
            jointcomp.Robot(urdf, base_link="link_1", tip_link="camera_link") as part:
        q = np.array(POSTURE)
        np.testing.assert_array_equal(at_flange.forward_kinematics(q), plain.forward_kinematics(q))
        tool0 = arm.forward_kinematics(q)
        flange = plain.forward_kinematics(q)
        np.testing.assert_allclose(tool0[:3, 3], flange[:3, 3] + 0.05 * flange[:3, 2], atol=1e-12)
        assert arm.dof == 6 and part.dof == 2
    with pytest.raises(jointcomp.FileError, match="tip link 'gripper' does not exist"):
        jointcomp.Robot(urdf, tip_link="gripper")
