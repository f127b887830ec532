"""Joint errors, compensation of points and trajectories, the spiral plan and the paper's experiment."""

import numpy as np
import pytest

import jointcomp
from conftest import POSTURE, RX170_URDF, UR10_URDF

SOFT = ('{"format": "jointcomp-parameters/1", "robot": "rx170", "effects": [{"type": "compliance", '
        '"stiffness_nm_per_rad": [1, 1, 1, 1, 1, 1]}]}')
GEARS = ('"gears": {"joints": [' + ", ".join(
    '{"joint": "joint_%d", "stage_ratios": %s}' % (j + 1, ratios)
    for j, ratios in enumerate(["[3.0, 40.0]", "[3.0, 40.0]", "[2.5, 40.0]", "[72.0]", "[64.0]", "[28.0]"])) + "]}")
WILD = ('{"format": "jointcomp-parameters/1", "robot": "rx170", ' + GEARS + ', "effects": [{"type": '
        '"transmission_error", "harmonics": [{"joint": "joint_2", "of": "motor", "cycles_per_revolution": 2, '
        '"amplitude_deg": 5, "phase_rad": 1}]}]}')


def test_prediction_by_effect(robot):
    velocity = [0.1, -0.1, 0.05, 0, 0, 0]
    np.testing.assert_array_equal(robot.predict_joint_errors(POSTURE, effects=""), np.zeros(6))
    compliance = robot.predict_joint_errors(POSTURE, velocity, effects="compliance")
    assert 1e-5 < abs(compliance[1]) < 1e-2
    everything = robot.predict_joint_errors(POSTURE)
    np.testing.assert_array_equal(robot.predict_joint_errors(POSTURE, effects=["compliance", "transmission_error"]),
                                  everything)
    assert not np.array_equal(everything, compliance)
    with pytest.raises(jointcomp.InvalidArgumentError, match="'bogus'"):
        robot.predict_joint_errors(POSTURE, effects="bogus")
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"velocity has shape \(2,\)"):
        robot.predict_joint_errors(POSTURE, velocity=[0, 0])
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"command has shape \(0,\)"):
        robot.predict_joint_errors([])


def test_compensation_inverts_the_prediction(robot):
    velocity = np.array([0.1, -0.1, 0.05, 0, 0, 0])
    reference, iterations = robot.compensate(POSTURE, velocity)
    assert iterations >= 2
    np.testing.assert_allclose(reference + robot.predict_joint_errors(reference, velocity), POSTURE, rtol=0, atol=1e-10)
    assert np.max(np.abs(reference - POSTURE)) > 1e-5
    unchanged, _ = robot.compensate(POSTURE, effects="")
    np.testing.assert_array_equal(unchanged, POSTURE)
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"planned\[3\] is NaN"):
        robot.compensate([0, 0, 0, np.nan, 0, 0])


def test_failing_solvers_raise():
    with jointcomp.Robot.from_json(RX170_URDF, SOFT) as soft:
        with pytest.raises(jointcomp.SolverError, match="did not settle"):
            soft.predict_joint_errors(POSTURE)
    with jointcomp.Robot.from_json(RX170_URDF, WILD) as wild:
        with pytest.raises(jointcomp.SolverError, match="did not converge"):
            wild.compensate(POSTURE)
        with pytest.raises(jointcomp.SolverError, match="trajectory point 0"):
            wild.compensate_trajectory([POSTURE, POSTURE])


def test_spiral_plan_and_trajectory_compensation(robot):
    m = robot.spiral_sample_count()
    plan = robot.spiral_plan()
    assert m > 1000
    assert plan.time.shape == (m,) and plan.tool_positions.shape == (m, 3)
    assert plan.q.shape == plan.qd.shape == (m, 6)
    np.testing.assert_allclose(plan.tool_positions[:, 2], 0.2, atol=1e-12)
    # Forward kinematics of the planned joints puts the tool on the planned path.
    for k in range(0, m, m // 5):
        np.testing.assert_allclose(robot.forward_kinematics(plan.q[k])[:3, 3], plan.tool_positions[k], atol=1e-9)
    result = robot.compensate_trajectory(plan.q, plan.qd)
    assert result.references.shape == (m, 6)
    assert result.max_iterations >= 2 and 1e-5 < result.max_correction < 1e-2
    for k in range(0, m, m // 5):
        reference, _ = robot.compensate(plan.q[k], plan.qd[k])
        np.testing.assert_array_equal(reference, result.references[k])
    # A flat array is not m rows: it is refused, never reinterpreted.
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"planned has shape \(%d,\)" % (6 * m)):
        robot.compensate_trajectory(plan.q.reshape(-1), effects="compliance")
    with pytest.raises(jointcomp.InvalidArgumentError, match="velocities has shape"):
        robot.compensate_trajectory(plan.q, plan.qd[:10])


def test_the_papers_experiment(robot, bare_robot):
    quasi_static = robot.spiral_experiment(use_plant=False)
    assert not quasi_static.use_plant and quasi_static.errors is None
    result = robot.spiral_experiment(errors=True)
    assert result.use_plant
    none, stiffness, both = result.metrics
    # The paper's reductions with both corrections: Ra 85 %, Rz 48 %; the stiffness correction alone less.
    assert both.ra < 0.15 * none.ra and both.rz < 0.52 * none.rz
    assert both.ra < stiffness.ra < none.ra
    assert 0.02e-3 < none.ra < 2e-3
    m = robot.spiral_sample_count()
    assert result.errors.shape == (3, m, 3)
    for run in range(3):
        assert jointcomp.accuracy_metrics(result.errors[run]) == result.metrics[run]
    again = robot.spiral_experiment(errors=False)
    assert again.metrics == result.metrics
    with pytest.raises(jointcomp.InvalidArgumentError, match="no \"plant\" object"):
        bare_robot.spiral_experiment(use_plant=True)
    assert bare_robot.spiral_experiment().use_plant is False


def test_an_unreachable_spiral():
    with jointcomp.Robot(UR10_URDF) as ur10:
        with pytest.raises(jointcomp.UnreachableError, match="path sample 0"):
            ur10.spiral_sample_count()
        with pytest.raises(jointcomp.UnreachableError):
            ur10.spiral_experiment()
