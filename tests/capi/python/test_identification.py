"""Identification, calibration and discovery through the bindings: round trips on simulated campaigns whose
truth is known (the truth differs from the nominal model, and the identified robot must come back to it),
determinism, saving, and the errors."""

import json

import numpy as np
import pytest

import jointcomp
from conftest import POSTURE, RX170_PARAMETERS, RX170_URDF

DEG = np.pi / 180.0


def parameters_with(edit):
    """The RX170's parameter file, changed by edit(document)."""
    document = json.loads(RX170_PARAMETERS.read_text())
    edit(document)
    return json.dumps(document)


def effect(document, kind):
    return next(e for e in document["effects"] if e["type"] == kind)


def without_joint2_harmonics(document):
    te = effect(document, "transmission_error")
    te["harmonics"] = [h for h in te["harmonics"] if h["joint"] != "joint_2"]


def joint2_harmonic(document, order):
    te = effect(document, "transmission_error")
    return next(h for h in te["harmonics"] if h["joint"] == "joint_2" and h["cycles_per_revolution"] == order)


def test_transmission_error_comes_back_to_the_truth(robot, tmp_path):
    sweep = jointcomp.simulate_campaign(robot, tmp_path / "sweep.csv", protocol="joint2-sweep", seed=11,
                                        step_deg=0.1)
    with jointcomp.Robot.from_json(RX170_URDF, parameters_with(without_joint2_harmonics)) as nominal:
        identified, report = jointcomp.identify_transmission_error(nominal, sweep, joint=2, stage=2)
        with identified:
            truth = json.loads(RX170_PARAMETERS.read_text())
            found = {h["cycles_per_revolution"]: h for h in report["harmonics"] if h["significant"]}
            for order, estimate in found.items():
                true = joint2_harmonic(truth, order)
                true_deg = true["amplitude_deg"] if "amplitude_deg" in true else true["amplitude_rad"] / DEG
                # Within 4 standard errors of the truth.
                assert abs(estimate["amplitude_deg"] - true_deg) < 4 * estimate["amplitude_se_deg"]
            assert 2.0 in found
            # The identified robot predicts the truth's kinematic error, which the nominal one lacked.
            truth_error = robot.predict_joint_errors(POSTURE, effects="transmission_error")[1]
            assert abs(nominal.predict_joint_errors(POSTURE, effects="transmission_error")[1] - truth_error) > 1e-5
            assert abs(identified.predict_joint_errors(POSTURE, effects="transmission_error")[1] - truth_error) < 3e-6
            assert "joint_2" in report.summary and report.data["identification"] == "transmission_error"


def test_stiffness_comes_back_to_the_truth(robot, tmp_path):
    campaign = jointcomp.simulate_campaign(robot, tmp_path / "stiffness.csv", protocol="stiffness", seed=12)
    truth = np.array(effect(json.loads(RX170_PARAMETERS.read_text()), "compliance")["stiffness_nm_per_rad"])

    def softer(document):
        compliance = effect(document, "compliance")
        compliance["stiffness_nm_per_rad"] = [k * 0.7 for k in compliance["stiffness_nm_per_rad"]]

    with jointcomp.Robot.from_json(RX170_URDF, parameters_with(softer)) as nominal:
        identified, report = jointcomp.identify_stiffness(nominal, campaign)
        with identified:
            estimates = report["joints"]
            covered = 0
            for joint, estimate in enumerate(estimates):
                low, high = estimate["local"]["stiffness_interval_nm_per_rad"]
                covered += low <= truth[joint] <= (np.inf if high is None else high)
            assert covered >= 5  # 95 % intervals: one miss in six is allowed
            written = effect(json.loads(identified.parameters_json()), "compliance")["stiffness_nm_per_rad"]
            assert np.allclose(written, truth, rtol=0.15)
            assert not np.allclose(written, truth * 0.7, rtol=0.1)


def offsets_truth(offsets):
    def edit(document):
        document["effects"].append({"type": "offset", "offset_rad": offsets})
    return parameters_with(edit)


def test_calibration_finds_joint_offsets_and_generalises(tmp_path):
    offsets = [0.0, 0.8e-3, -0.6e-3, 0.5e-3, 0.0, 0.0]
    with jointcomp.Robot.from_json(RX170_URDF, offsets_truth(offsets)) as truth, \
            jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as nominal:
        fit = jointcomp.simulate_campaign(truth, tmp_path / "fit.csv", protocol="random", seed=21, count=120)
        held = jointcomp.simulate_campaign(truth, tmp_path / "held.csv", protocol="random", seed=22, count=60)
        heard = []
        jointcomp.set_progress(heard.append)
        try:
            calibrated, report = jointcomp.calibrate(nominal, fit, [held])
        finally:
            jointcomp.set_progress(None)
        # The calibration said what it was doing: its rows and parameters, then each accepted step.
        assert any("120 rows" in m and "parameters identifiable" in m for m in heard), heard
        assert any("calibrating: iteration 1, RMS" in m for m in heard), heard
        told = len(heard)
        jointcomp.calibrate(nominal, fit, [held])[0].close()  # silenced: nothing more is heard
        assert len(heard) == told
        with pytest.raises(TypeError):
            jointcomp.set_progress(42)
        with calibrated:
            holdout = next(c for c in report["campaigns"] if c["file"] == str(held))
            assert holdout["after"]["rms_mm"] < 0.3 * holdout["before"]["rms_mm"]
            values = {p["name"]: p for p in report["parameters"]}
            for joint in (2, 3):
                estimate = values["joint_%d.offset_rad" % joint]
                if estimate["identified"]:
                    assert abs(estimate["value"] - offsets[joint - 1]) < 5 * estimate["sigma"] + 2e-5
            # Saved and loaded again, the calibrated robot is the same robot.
            calibrated.save(tmp_path / "calibrated.urdf", tmp_path / "calibrated.json")
            with jointcomp.Robot(tmp_path / "calibrated.urdf", tmp_path / "calibrated.json") as reloaded:
                assert np.allclose(reloaded.forward_kinematics(POSTURE), calibrated.forward_kinematics(POSTURE),
                                   atol=1e-12, rtol=0)
                assert np.allclose(reloaded.predict_joint_errors(POSTURE), calibrated.predict_joint_errors(POSTURE),
                                   atol=1e-12, rtol=0)
            # The fitted target on the flange, as the report gives it, kept through the files.
            target = [values["target.%s_m" % axis]["value"] for axis in "xyz"]
            assert np.array_equal(calibrated.tool_target, target), (calibrated.tool_target, target)
            assert calibrated.base_frame is None  # simulated in the base frame: no instrument's frame
            with jointcomp.Robot(tmp_path / "calibrated.urdf", tmp_path / "calibrated.json") as reloaded:
                assert np.array_equal(reloaded.tool_target, calibrated.tool_target)
                assert reloaded.base_frame is None
        with jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as plain:
            assert plain.tool_target is None and plain.base_frame is None
        # Both campaigns in one calibration: each is reported (simulated in the base frame: one set-up).
        both, report = jointcomp.calibrate(nominal, [fit, held])
        with both:
            fitted = [c for c in report["campaigns"] if c["role"] == "calibration"]
            assert [(c["file"], c["rows"]) for c in fitted] == [(str(fit), 120), (str(held), 60)]
            assert report["rows"]["used"] == 180
            assert [s["campaigns"] for s in report["instrument_setups"]] == [[str(fit), str(held)]]
        with pytest.raises(jointcomp.InvalidArgumentError, match="campaign_path names no file"):
            jointcomp.calibrate(nominal, [])


def test_discovery_names_the_missing_offset_and_is_deterministic(tmp_path):
    offsets = [0.0, 0.0, 1.0e-3, 0.0, 0.0, 0.0]
    with jointcomp.Robot.from_json(RX170_URDF, offsets_truth(offsets)) as truth, \
            jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as nominal:
        fit = jointcomp.simulate_campaign(truth, tmp_path / "fit.csv", protocol="random", seed=31, count=150)
        held = jointcomp.simulate_campaign(truth, tmp_path / "held.csv", protocol="random", seed=32, count=60)
        runs = []
        for _ in range(2):
            extended, report = jointcomp.discover(nominal, [fit], [held], base="frame", types=["offset", "harmonic"],
                                                  max_steps=3)
            with extended:
                runs.append((extended.parameters_json(), report))
        (parameters, report), (parameters_again, _) = runs
        assert parameters == parameters_again
        first = report["steps"][0]
        assert first["type"] == "offset" and first["joint_index"] == 3
        final = report["final"]["held_out"][0]["rms_mm"]
        assert final < 0.5 * report["initial"]["held_out"][0]["rms_mm"]
        assert report["noise_floor"]["final_over_floor"] < 1.3
        # Without base, discovery starts from the textbook calibration, as `jointcomp discover` does.
        extended, default = jointcomp.discover(nominal, [fit], [held], types=["offset"], max_steps=1)
        with extended:
            assert default["selection"]["base"] == "textbook"


def test_bad_options_and_files_raise_named_errors(robot, tmp_path):
    with pytest.raises(jointcomp.InvalidArgumentError, match="options_json.speed"):
        jointcomp.simulate_campaign(robot, tmp_path / "x.csv", protocol="random", speed=3)
    with pytest.raises(jointcomp.InvalidArgumentError, match="unknown protocol 'circle'"):
        jointcomp.simulate_campaign(robot, tmp_path / "x.csv", protocol="circle")
    with pytest.raises(jointcomp.FileError, match="missing.csv"):
        jointcomp.identify_stiffness(robot, tmp_path / "missing.csv")
    with pytest.raises(jointcomp.InvalidArgumentError, match="options_json.method"):
        jointcomp.identify_stiffness(robot, tmp_path / "missing.csv", method="best")
    with pytest.raises(jointcomp.InvalidArgumentError, match="options_json.stage"):
        jointcomp.identify_transmission_error(robot, tmp_path / "missing.csv", stage=0)
    with pytest.raises(jointcomp.InvalidArgumentError, match="unknown effect type 'gremlin'"):
        jointcomp.discover(robot, [tmp_path / "missing.csv"], types=["gremlin"])
    with pytest.raises(jointcomp.InvalidArgumentError, match="campaign_paths names no file"):
        jointcomp.discover(robot, [])
    with pytest.raises(ValueError, match="newline"):
        jointcomp.calibrate(robot, tmp_path / "fit.csv", ["a\nb.csv"])
    with pytest.raises(jointcomp.InvalidArgumentError, match="both NULL"):
        robot.save()
    assert not (tmp_path / "x.csv").exists()  # nothing written by a refused call


def test_identify_and_compensate_beats_the_nominal_model_and_refuses_bad_input(robot, bare_robot):
    """The paper's whole method on a truth of the caller's (a stiffer joint 2, a stronger balancer spring):
    the identified model, measured on that truth, leaves less Ra after both corrections than the nominal one;
    the identified robot carries the truth's joint-2 stiffness within its stated interval."""
    def changed(document):
        effect(document, "compliance")["stiffness_nm_per_rad"][1] *= 1.04
        effect(document, "spring_balancer")["stiffness_n_per_m"] *= 1.03

    with jointcomp.Robot.from_json(RX170_URDF, parameters_with(changed)) as truth:
        nominal_runs = robot.spiral_experiment(use_plant=False, truth=truth).metrics
        identified, metrics, report = jointcomp.identify_and_compensate(robot, truth, seed=11)
        with identified:
            assert metrics[2].ra < 0.5 * nominal_runs[2].ra, (metrics[2], nominal_runs[2])
            joint2 = report.data["reports"][0]["joints"][1]["local"]
            low, high = joint2["stiffness_interval_nm_per_rad"]
            assert low <= 850000.0 * 1.04 <= high, joint2
        with pytest.raises(jointcomp.InvalidArgumentError, match="feed_rate_m_per_s"):
            jointcomp.identify_and_compensate(robot, truth, feed_rate_m_per_s=50)
        with pytest.raises(jointcomp.InvalidArgumentError, match="use_plant"):
            jointcomp.identify_and_compensate(robot, bare_robot, use_plant=True)
        with pytest.raises(TypeError, match="truth must be a jointcomp.Robot"):
            jointcomp.identify_and_compensate(robot, "truth.json")


def _rotation(rx, ry, rz):
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    return (np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]) @
            np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]]))


def test_calibration_in_an_instrument_frame_exposes_the_base_frame(tmp_path):
    """A campaign measured in a tracker's frame: the calibrated handle holds the base's pose in it (the
    report's frame.* values), the target, and both survive jc_robot_save and loading."""
    with jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as nominal:
        base = jointcomp.simulate_campaign(nominal, tmp_path / "base.csv", protocol="random", seed=31, count=80)
        rotation, translation = _rotation(0.02, -0.01, 0.6), np.array([1.2, -0.4, 0.3])
        lines, head = [], None
        for line in base.read_text().splitlines():
            if line.startswith("# frame:"):
                line = "# frame: instrument"
            elif not line.startswith("#"):
                cells = line.split(",")
                if head is None:
                    head = cells
                else:
                    at = [head.index(c) for c in "xyz"]
                    moved = rotation @ (np.array([float(cells[k]) for k in at]) * 1e-3) + translation
                    for k, v in zip(at, moved):
                        cells[k] = repr(float(v) * 1e3)
                    line = ",".join(cells)
            lines.append(line)
        moved_path = tmp_path / "tracker.csv"
        moved_path.write_text("\n".join(lines) + "\n")
        calibrated, report = jointcomp.calibrate(nominal, moved_path)
        with calibrated:
            values = {p["name"]: p["value"] for p in report["parameters"]}
            pose = calibrated.base_frame
            assert pose is not None
            assert np.array_equal(pose[:3, 3], [values["frame.t%s_m" % a] for a in "xyz"]), pose
            # The nominal robot measured from a known frame: the fit finds it (to the noise).
            assert np.abs(pose[:3, :3] - rotation).max() < 1e-4 and np.abs(pose[:3, 3] - translation).max() < 1e-4
            calibrated.save(tmp_path / "c.urdf", tmp_path / "c.json")
            assert "_measurement_frame" in (tmp_path / "c.urdf").read_text()
            assert json.loads(calibrated.parameters_json())["base_frame"]["link"] == "base_link_measurement_frame"
            with jointcomp.Robot(tmp_path / "c.urdf", tmp_path / "c.json") as reloaded:
                assert np.abs(reloaded.base_frame - pose).max() < 1e-14
                assert np.array_equal(reloaded.tool_target, calibrated.tool_target)
                assert np.allclose(reloaded.forward_kinematics(POSTURE), calibrated.forward_kinematics(POSTURE),
                                   atol=1e-12, rtol=0)
