"""jointcomp.distributed: Monte Carlo and fleet calibration on a Dask LocalCluster of two worker processes.

The quasi-static robot and a few draws keep the file short (the plant is not the point here): one cluster
serves every test, and the serial runs (this process, no Dask) are the reference the cluster's results must
equal bit for bit.
"""

import json

import numpy as np
import pytest

import jointcomp
from jointcomp import distributed as jd

from conftest import RX170_PARAMETERS, RX170_URDF

SAMPLES = 4


@pytest.fixture(scope="module")
def client():
    with jd.cluster(n_workers=2, start_timeout=120) as connected:
        yield connected


@pytest.fixture(scope="module")
def serial_result():
    return jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True)


def test_a_given_truth_is_followed_and_the_nominal_compensates(robot):
    # The truth equal to the nominal: the full compensation leaves the tracker's noise and the
    # compensation's residue only; a drawn truth leaves more.
    itself = robot.spiral_experiment(use_plant=False, truth=robot)
    assert itself.metrics[2].rms < 0.1 * itself.metrics[0].rms
    parameters, urdf, _ = jd.draw_parameters(robot.parameters_json(), None,
                                             jd.main_job_distribution(robot.parameters_json()), 7, 0)
    assert urdf is None
    with jointcomp.Robot.from_json(RX170_URDF, parameters) as truth:
        drawn = robot.spiral_experiment(use_plant=False, truth=truth, errors=True)
    assert drawn.metrics[2].rms > itself.metrics[2].rms
    assert drawn.errors.shape == (3, robot.spiral_sample_count(), 3)
    with pytest.raises(TypeError, match="truth must be a jointcomp.Robot"):
        robot.spiral_experiment(truth="rx170.json")
    with pytest.raises(jointcomp.InvalidArgumentError, match="truth"):
        robot.spiral_experiment(use_plant=True, truth=jointcomp.Robot(RX170_URDF))


def test_draws_depend_on_seed_and_index_only():
    text = RX170_PARAMETERS.read_text()
    law = jd.main_job_distribution(text)
    # The main job's law: 6 stiffnesses, 4 harmonics x (amplitude, phase), the balancer's 6 numbers.
    assert len(law) == 6 + 8 + 6
    first = jd.draw_parameters(text, None, law, 7, 3)
    assert first == jd.draw_parameters(text, None, law, 7, 3)
    assert first != jd.draw_parameters(text, None, law, 7, 4)
    assert first != jd.draw_parameters(text, None, law, 8, 3)
    stiffness = json.loads(first[0])["effects"][0]["stiffness_nm_per_rad"]
    nominal = json.loads(text)["effects"][0]["stiffness_nm_per_rad"]
    assert all(abs(s / n - 1) <= 0.05 for s, n in zip(stiffness, nominal))


def test_two_workers_equal_the_serial_run_bit_for_bit(client, serial_result, tmp_path):
    result = jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, client=client)
    assert not result.failed and not serial_result.failed
    assert np.array_equal(result.metrics, serial_result.metrics)
    assert np.array_equal(result.band_norm, serial_result.band_norm)
    assert np.array_equal(result.band_z, serial_result.band_z)
    stats = result.statistics()
    # The compensation helps in every percentile of the max error.
    for p in ("p5", "p50", "p95"):
        assert stats["compensated"]["max"][p] < stats["uncompensated"]["max"][p]
    result.write(tmp_path)
    document = json.loads((tmp_path / "montecarlo.json").read_text())
    assert document["succeeded"] == SAMPLES and len(document["per_draw_m"]["compensated"]) == SAMPLES
    assert (tmp_path / "montecarlo_band.png").stat().st_size > 10000
    assert len((tmp_path / "montecarlo.csv").read_text().splitlines()) == SAMPLES + 1
    assert "within" in result.summary()


def test_one_worker_of_its_own_cluster_equals_the_serial_run(serial_result):
    result = jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, n_workers=1, start_timeout=120)
    assert np.array_equal(result.metrics, serial_result.metrics)


def test_a_worker_killed_mid_run_loses_no_draw(client, serial_result, tmp_path):
    marker = tmp_path / "killed"
    result = jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, client=client,
                            _kill_marker=marker, timeout=120)
    assert marker.read_text() == "killed once\n"  # the first attempt of draw 0 did kill its worker
    assert not result.failed
    assert np.array_equal(result.metrics, serial_result.metrics)


def test_a_calibration_report_gives_the_law(robot, tmp_path):
    campaign = tmp_path / "poses.csv"
    jointcomp.simulate_campaign(robot, campaign, protocol="random", seed=3, count=40)
    calibrated, report = jointcomp.calibrate(robot, campaign)
    with calibrated:
        calibrated.save(tmp_path / "calibrated.urdf", tmp_path / "calibrated.json")
    (tmp_path / "report.json").write_text(report.json)
    law, left = jd.report_distribution(tmp_path / "report.json")
    names = {e["parameter"] for e in law if "parameter" in e}
    assert "joint_2.offset_rad" in names and "joint_2.compliance_rad_per_nm" in names
    assert any(item.startswith("target.") for item in left)
    result = jd.monte_carlo(tmp_path / "calibrated.urdf", tmp_path / "calibrated.json",
                            report=tmp_path / "report.json", samples=2, seed=1, serial=True)
    assert not result.failed
    print(result.summary())
    # Calibration's uncertainty is microns: the compensated path stays far inside the uncompensated one.
    stats = result.statistics()
    assert stats["compensated"]["max"]["p95"] < 0.5 * stats["uncompensated"]["max"]["p5"]


def test_a_drawn_geometry_moves_the_urdf():
    urdf = RX170_URDF.read_text()
    law = [{"parameter": "joint_2.placement_dz_m", "law": "normal", "scale": 1e-3}]
    _, moved, _ = jd.draw_parameters(RX170_PARAMETERS.read_text(), urdf, jd.check_distribution(law), 1, 0)
    assert moved is not None and moved != urdf


def test_bad_inputs_are_named(tmp_path):
    with pytest.raises(jd.DistributedError, match="report: .*nothing.json does not exist"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, report=tmp_path / "nothing.json", samples=2, serial=True)
    for samples in (0, -1, 2.5, jd.MAX_SAMPLES + 1, 2**30):
        with pytest.raises(jd.DistributedError, match="samples is .*, must be an integer from 1 to 10000"):
            jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=samples, serial=True)
    with pytest.raises(jd.DistributedError, match="parameters: .*missing.json does not exist"):
        jd.monte_carlo(RX170_URDF, tmp_path / "missing.json", samples=2, serial=True)
    with pytest.raises(jd.DistributedError, match="entry 0: parameter 'joint_2.stifness' is none of"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=2, serial=True,
                       distribution=[{"parameter": "joint_2.stifness", "scale": 0.1}])
    with pytest.raises(jd.DistributedError, match="joint_9.stiffness_nm_per_rad: the parameters have no compliance"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=2, serial=True,
                       distribution=[{"parameter": "joint_9.stiffness_nm_per_rad", "scale": 0.1}])
    with pytest.raises(jd.DistributedError, match="campaign files that do not exist: .*absent.csv"):
        jd.fleet(RX170_URDF, RX170_PARAMETERS, [tmp_path / "absent.csv"], tmp_path / "out", serial=True)
    with pytest.raises(jd.DistributedError, match="scheduler tcp://127.0.0.1:9: no connection within 2 s"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=1, scheduler="tcp://127.0.0.1:9", start_timeout=2)


def test_fleet_writes_a_folder_per_robot_and_the_summary(robot, client, tmp_path):
    campaigns = []
    for k in range(3):
        parameters, _, _ = jd.draw_parameters(robot.parameters_json(), None,
                                              jd.main_job_distribution(robot.parameters_json()), 11, k)
        with jointcomp.Robot.from_json(RX170_URDF, parameters) as truth:
            campaigns.append(jointcomp.simulate_campaign(truth, tmp_path / ("robot%d.csv" % k), protocol="random",
                                                         seed=k + 1, count=30))
    broken = tmp_path / "broken.csv"
    broken.write_text("not a campaign\n")
    result = jd.fleet(RX170_URDF, RX170_PARAMETERS, campaigns + [broken], tmp_path / "fleet", client=client)
    assert [r["name"] for r in result.robots] == ["robot0", "robot1", "robot2", "broken"]
    assert "broken.csv" in result.robots[3]["error"] and len(result.failed) == 1
    for k in range(3):
        folder = tmp_path / "fleet" / ("robot%d" % k)
        assert json.loads((folder / "report.json").read_text())["format"] == "jointcomp-calibration-report/1"
        assert (folder / "calibrated.urdf").is_file() and (folder / "calibrated.json").is_file()
        assert result.robots[k]["after"]["rms_mm"] <= result.robots[k]["before"]["rms_mm"]
    assert len((tmp_path / "fleet" / "fleet_summary.csv").read_text().splitlines()) == 5
    summary = json.loads((tmp_path / "fleet" / "fleet_summary.json").read_text())
    assert summary["failed"] == ["broken"] and summary["outlier_rule"] == jd.OUTLIER_RULE
    assert (tmp_path / "fleet" / "fleet.png").is_file()


def test_the_outlier_rule():
    robots = [{"name": "r%d" % k, "campaign": "c", "before": {"rms_mm": 1.0, "mean_mm": 1.0, "max_mm": 2.0},
               "after": {"rms_mm": value, "mean_mm": value, "max_mm": value}}
              for k, value in enumerate([0.40, 0.42, 0.41, 0.43, 0.39, 0.90])]
    result = jd.FleetResult("calibrate", robots)
    # median 0.415, MAD 0.015: threshold 0.415 + 3 x 1.4826 x 0.015 = 0.4817 mm
    assert result.threshold_mm == pytest.approx(0.415 + 3 * 1.4826 * 0.015)
    assert [r["name"] for r in robots if r["outlier"]] == ["r5"]


def test_correlated_draws_follow_the_correlation():
    parameters = RX170_PARAMETERS.read_text()
    law = jd.check_distribution([
        {"parameter": "joint_2.stiffness_nm_per_rad", "law": "normal", "scale": 1000.0},
        {"parameter": "joint_3.stiffness_nm_per_rad", "law": "normal", "scale": 2000.0},
        {"correlation": {"parameters": ["joint_2.stiffness_nm_per_rad", "joint_3.stiffness_nm_per_rad"],
                         "matrix": [[1.0, -0.9], [-0.9, 1.0]]}}])
    nominal = next(e for e in json.loads(parameters)["effects"] if e["type"] == "compliance")["stiffness_nm_per_rad"]
    moves = []
    for k in range(600):
        drawn, _, _ = jd.draw_parameters(parameters, None, law, 11, k)
        stiffness = next(e for e in json.loads(drawn)["effects"] if e["type"] == "compliance")["stiffness_nm_per_rad"]
        moves.append((stiffness[1] - nominal[1], stiffness[2] - nominal[2]))
    moves = np.array(moves)
    assert np.corrcoef(moves.T)[0, 1] == pytest.approx(-0.9, abs=0.03)
    assert np.std(moves[:, 0]) == pytest.approx(1000.0, rel=0.1)
    assert np.std(moves[:, 1]) == pytest.approx(2000.0, rel=0.1)
    for bad, message in (([[1.0, 1.5], [1.5, 1.0]], "not a correlation matrix"),
                         ([[1.0, 0.2], [0.3, 1.0]], "symmetric"),
                         ([[1.0, 0.2]], "must be 2 x 2")):
        with pytest.raises(jd.DistributedError, match=message):
            jd.check_distribution(law[:2] + [{"correlation": {"parameters": law[2]["correlation"]["parameters"],
                                                               "matrix": bad}}])


def test_a_calibration_report_carries_its_correlation(robot, tmp_path):
    campaign = tmp_path / "poses.csv"
    jointcomp.simulate_campaign(robot, campaign, protocol="random", seed=5, count=60)
    _, report = jointcomp.calibrate(robot, campaign)
    data = json.loads(report.json)
    correlation = np.array(data["correlation"]["matrix"])
    assert correlation.shape[0] == len(data["correlation"]["parameters"]) >= 2
    np.testing.assert_allclose(np.diag(correlation), 1.0)
    assert np.max(np.abs(correlation - np.eye(len(correlation)))) > 0.1  # some parameters do trade off
    law, _ = jd.report_distribution(data)
    blocks = [e["correlation"] for e in law if "correlation" in e]
    assert len(blocks) == 1 and all(name in {e.get("parameter") for e in law} for name in blocks[0]["parameters"])


def test_output_names_from_user_data_are_plain_file_names():
    from jointcomp._paths import plain_file_name
    assert plain_file_name("..") == "robot" and plain_file_name("...") == "robot" and plain_file_name("") == "robot"
    assert plain_file_name("../../victim") == "_.._victim"
    assert plain_file_name("a/b\\c d\nе") == "a_b_c_d__"
    assert plain_file_name(".hidden") == "hidden" and plain_file_name("r1-arm_2.v3") == "r1-arm_2.v3"
    assert len(plain_file_name("x" * 10000)) == 64


def test_fleet_writes_only_inside_out_whatever_the_campaigns_are_named(robot, tmp_path):
    # A campaign named "...csv" has the stem "..": its folder was out/.., the user's own folder.
    campaign = jointcomp.simulate_campaign(robot, tmp_path / "...csv", protocol="random", seed=1, count=30)
    out = tmp_path / "deep" / "out"
    result = jd.fleet(RX170_URDF, RX170_PARAMETERS, [campaign], out, serial=True)
    assert [r["name"] for r in result.robots] == ["robot"] and not result.failed
    assert (out / "robot" / "report.json").is_file()
    assert sorted(p.name for p in (tmp_path / "deep").iterdir()) == ["out"]


def test_out_is_checked_before_any_work(tmp_path, monkeypatch, capsys):
    def no_work(*arguments, **keywords):
        raise AssertionError("work started before --out was checked")
    monkeypatch.setattr(jd, "_run_tasks", no_work)
    monkeypatch.setattr(jd, "monte_carlo", no_work)
    a_file = tmp_path / "a_file"
    a_file.write_text("not a folder\n")
    campaign = tmp_path / "c.csv"
    campaign.write_text("# a campaign\n")
    for out, message in ((a_file, "exists and is not a folder"), (a_file / "below", "cannot be created"),
                         ("/proc/jointcomp-out", "cannot be created"), ("", "the path is empty")):
        with pytest.raises(jd.DistributedError, match=message):
            jd.fleet(RX170_URDF, RX170_PARAMETERS, [campaign], out, serial=True)
        robot_files = ["--urdf", str(RX170_URDF), "--params", str(RX170_PARAMETERS)]
        assert jd.main(["montecarlo"] + robot_files + ["--out", str(out)]) == 1
        assert "--out: " in capsys.readouterr().err
        assert jd.main(["fleet"] + robot_files + ["--campaign", str(campaign), "--out", str(out)]) == 1
        assert message in capsys.readouterr().err


def test_a_writer_killed_part_way_leaves_nothing_behind(tmp_path):
    # Every output of montecarlo and fleet: whole or absent, and no ".name.tmpPID" left by a kill.
    import subprocess
    import sys
    from jointcomp._paths import write_atomically
    write_atomically(tmp_path / "a.txt", lambda stream: stream.write(b"first\n"))
    write_atomically(tmp_path / "a.txt", lambda stream: stream.write(b"second\n"))
    assert (tmp_path / "a.txt").read_text() == "second\n" and (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
    dying = ("import os, signal, sys\n"
             "from jointcomp._paths import write_atomically\n"
             "def write(stream):\n"
             "    stream.write(b'half')\n"
             "    stream.flush()\n"
             "    os.kill(os.getpid(), signal.SIGKILL)\n"
             "write_atomically(sys.argv[1], write)\n")
    status = subprocess.run([sys.executable, "-c", dying, str(tmp_path / "a.txt")]).returncode
    assert status == -9
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"] and (tmp_path / "a.txt").read_text() == "second\n"


def test_a_timeout_that_is_no_number_of_seconds_is_refused(capsys):
    for timeout in ("nan", "-1", "0", "inf"):
        assert jd.main(["montecarlo", "--urdf", str(RX170_URDF), "--params", str(RX170_PARAMETERS),
                        "--timeout", timeout, "--out", "unused"]) == 1
        assert "--timeout is" in capsys.readouterr().err
