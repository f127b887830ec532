"""jointcomp.distributed: Monte Carlo and fleet calibration, serial and on a Dask LocalCluster of two workers.

The quasi-static robot and a few draws keep the file short: one cluster serves most tests, and the serial
runs (this process, no Dask) are the reference the cluster's results must equal byte for byte.
"""

import contextlib
import io
import json
import math
import os
import pathlib
import pickle
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

import jointcomp
from jointcomp import distributed as jd
from jointcomp.distributed import laws, montecarlo, streaming, summary as summaries

from conftest import RX170_PARAMETERS, RX170_URDF

SAMPLES = 6


@pytest.fixture(scope="module")
def client():
    with jd.cluster(n_workers=2, start_timeout=120) as connected:
        yield connected


@pytest.fixture(scope="module")
def spiral():
    with jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as nominal:
        job = jointcomp.SpiralJob(nominal)
    yield job
    job.close()


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    result = jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=out,
                            batch_size=4)
    return result, out


def _bytes(folder):
    return {name: (folder / name).read_bytes() for name in ("montecarlo.json", "montecarlo.csv", "montecarlo_band.png")}


def test_the_job_with_the_nominal_values_is_the_experiment_with_the_nominal_truth(robot, spiral):
    # The documented identity: one draw of the job at the nominal values and tracker seed 7 (the default of
    # jc_spiral_experiment_truth) is that call with the nominal robot as its own truth, bit for bit.
    errors = np.empty((3, spiral.samples, 3))
    metrics = spiral.run(spiral.nominal_values, 7, errors)
    reference = robot.spiral_experiment(use_plant=False, truth=robot, errors=True)
    assert np.array_equal(metrics, np.array([list(m) for m in reference.metrics]))
    assert np.array_equal(errors, reference.errors)
    assert np.array_equal(spiral.time(), robot.spiral_plan().time)
    # Another tracker seed gives other noise, the same compensation.
    assert not np.array_equal(spiral.run(spiral.nominal_values, 8), metrics)


def test_a_drawn_geometry_is_the_urdf_moved_by_it(spiral):
    # joint_3's origin is rpy (0, 0, pi/2): an offset d and a placement dx are, in the URDF, a yaw of
    # pi/2 + offset and the origin moved by Rz(pi/2) (dx, 0, 0) = (0, dx, 0). Derived independently of the
    # library's origin * Trans(d) * Exp(r) * Rot(axis, offset).
    offset, dx = 2e-3, 1.5e-3
    values = spiral.nominal_values.copy()
    values[spiral.index["joint_3.offset_rad"]] = offset
    values[spiral.index["joint_3.placement_dx_m"]] = dx
    drawn = spiral.run(values, 7)
    text = RX170_URDF.read_text().replace('<origin xyz="0.825 0 0" rpy="0 0 1.5707963267948966"/>',
                                          '<origin xyz="0.825 %r 0" rpy="0 0 %r"/>' % (dx, math.pi / 2 + offset))
    assert text != RX170_URDF.read_text()
    with jointcomp.Robot(RX170_URDF, RX170_PARAMETERS) as nominal, \
            jointcomp.Robot.from_text(text, RX170_PARAMETERS.read_text()) as moved:
        expected = nominal.spiral_experiment(use_plant=False, truth=moved)
    assert np.allclose(drawn, [list(m) for m in expected.metrics], rtol=1e-7, atol=1e-12)
    assert drawn[0, 2] > 1.2 * spiral.run(spiral.nominal_values, 7)[0, 2]


def test_the_seed_scheme_is_the_documented_one(spiral):
    # Draw k of seed s, built here by hand from SeedSequence([s, k]): one uniform(-1, 1) per entry of the
    # main job's law (all uniform), in order, then the tracker's seed. A stream shifted to k + 1 fails.
    law = jd.main_job_distribution(spiral)
    bound = laws.BoundLaw(law, spiral)
    generator = np.random.Generator(np.random.PCG64(np.random.SeedSequence([7, 3])))
    uniforms = [generator.uniform(-1.0, 1.0) for _ in law]
    noise_seed = int(generator.integers(0, 2 ** 62))
    expected = spiral.nominal_values.copy()
    for entry, u in zip(law, uniforms):
        k = spiral.index[entry["parameter"]]
        expected[k] = expected[k] * (1 + entry["scale"] * u) if entry["relative"] else expected[k] + entry["scale"] * u
    values, seed, clamped = bound.draw(7, 3)
    assert np.array_equal(values, expected) and seed == noise_seed and clamped == 0
    assert not np.array_equal(bound.draw(7, 4)[0], expected)
    # The task's draw 3 is the job run with these values and that tracker seed.
    job = {"key": "seed-scheme", "urdf_text": RX170_URDF.read_text(), "parameters_json": RX170_PARAMETERS.read_text(),
           "distribution": law, "seed": 7, "use_plant": False, "band_points": 10}
    batch = montecarlo._batch_task(job, (3, 4))
    assert np.array_equal(batch["metrics"][0], spiral.run(expected, noise_seed))


def test_the_main_job_law_is_the_libraries(spiral):
    # Every effect parameter has the library's law; the perturbed experiment's truth lies inside it.
    law = {e["parameter"]: e for e in jd.main_job_distribution(spiral)}
    assert len(law) == 6 + 8 + 6  # 6 stiffnesses, 4 harmonics x (amplitude, phase), the balancer's 6 numbers
    assert all(e["law"] == "uniform" and e["scale"] > 0 for e in law.values())
    assert not any(name.endswith(("offset_rad", "_m")) and ".placement" in name for name in law)


def test_a_summary_is_exact_counts_whatever_the_batching():
    rng = np.random.default_rng(5)
    draws = [(rng.lognormal(-9, 0.5, (3, 5)), rng.normal(0, 1e-4, (3, 8)), rng.lognormal(-9, 0.3, (3, 8)))
             for _ in range(50)]
    whole, parts = summaries.Summary(8), [summaries.Summary(8) for _ in range(3)]
    for k, draw in enumerate(draws):
        whole.add_draw(*draw)
        parts[k % 3].add_draw(*draw)
    merged = summaries.Summary(8)
    for part in reversed(parts):
        merged.merge(part)
    travelled = pickle.loads(pickle.dumps(merged))  # as Dask ships it: the counts sparse
    assert len(pickle.dumps(merged)) < 0.1 * sum(getattr(merged, k).nbytes for k in ("metrics", "band_norm", "band_z"))
    # Batches merged as they arrive (still packed), and a checkpoint read back, are the same counts.
    arrived = summaries.Summary(8)
    for part in parts:
        arrived.merge(pickle.loads(pickle.dumps(part)))
    stored = io.BytesIO()
    np.savez(stored, **arrived.arrays())
    stored.seek(0)
    with np.load(stored) as arrays:
        resumed = summaries.Summary.from_arrays(arrays, [])
    for key, value in whole.arrays().items():
        for other in (merged, travelled, arrived, resumed):
            assert np.array_equal(value, other.arrays()[key]), key
    for key in ("metrics", "band_norm", "band_z"):  # and dense when read
        assert np.array_equal(getattr(whole, key), getattr(travelled, key)), key
        assert np.array_equal(getattr(whole, key), getattr(resumed, key)), key
    # A percentile read from the bins is the nearest-rank percentile of the draws within the bins' 0.05 %.
    values = np.array([d[0][2, 3] for d in draws])
    for p in (5, 50, 95):
        exact = np.percentile(values, p, method="inverted_cdf")
        assert abs(merged.percentile(2, 3, p)[0] / exact - 1) <= 0.0005 + 1e-12
    # The band's percentiles at each point, signed Z and norm, are the draws' own within the bins' 2.5 %.
    band_z, band_norm = arrived.band()
    for band, values in ((band_z, np.array([d[1] for d in draws])), (band_norm, np.array([d[2] for d in draws]))):
        for i, p in enumerate(summaries.PERCENTILES):
            exact = np.percentile(values, p, axis=0, method="inverted_cdf")
            assert np.all(np.abs(band[:, i, :] - exact) <= 0.025 * np.abs(exact) + summaries.BAND_LOW)


def test_percentile_intervals_are_the_binomial_ones():
    # Brute force from the binomial law: P(X_(l) <= x_q <= X_(u)) >= 95 % with equal tails.
    for n, q in ((100, 0.95), (40, 0.5), (300, 0.05)):
        cdf = np.cumsum([math.comb(n, k) * q ** k * (1 - q) ** (n - k) for k in range(n + 1)])
        lower, upper = summaries.confidence_ranks(n, q)
        assert cdf[lower - 1] <= 0.025 < cdf[lower]
        assert cdf[upper - 1] >= 0.975 > cdf[upper - 2]
    assert summaries.smallest_sample(0.95) == 72
    assert summaries.confidence_ranks(71, 0.95)[1] is None
    assert summaries.confidence_ranks(72, 0.95)[1] == 72


def test_two_workers_equal_the_serial_run_byte_for_byte(client, serial_run, tmp_path):
    serial, serial_out = serial_run
    result = jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, client=client, out=tmp_path,
                            batch_size=1)
    assert _bytes(tmp_path) == _bytes(serial_out)
    stats = result.statistics()
    for p in ("p5", "p50", "p95"):  # the compensation helps in every percentile of the max error
        assert stats["compensated"]["max"][p]["mm"] < stats["uncompensated"]["max"][p]["mm"]
    document = json.loads((tmp_path / "montecarlo.json").read_text())
    assert document["units"] == "mm" and document["succeeded"] == SAMPLES
    assert document["warnings"] and "too few" in document["warnings"][0]  # 6 draws cannot bound a 95th percentile
    assert document["runs"]["compensated"]["max"]["p95"]["ci_mm"][1] is None
    rows = (tmp_path / "montecarlo.csv").read_text().splitlines()
    assert len(rows) == SAMPLES + 1
    # The CSV's metrics are the draws' own, in mm.
    values = [float(v) for v in rows[1 + 2].split(",")[1:13]]
    assert min(values) > 1e-4 and max(values) < 10
    assert not list(tmp_path.glob("*.checkpoint.npz"))


def test_the_scheduler_holds_only_the_tasks_in_flight(client):
    # Twice as many as there are workers; a task whose result the client took is released at once.
    scheduler, held = client.cluster.scheduler, []
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=12, seed=7, client=client, batch_size=1,
                   progress=lambda done, total, rate: held.append(len(scheduler.tasks)))
    # + 3: a release reaches the scheduler a moment later (without the bound all 12 would be there at once)
    assert len(held) == 12 and max(held) <= 2 * 2 + 3, held
    deadline = time.monotonic() + 10.0
    while scheduler.tasks and time.monotonic() < deadline:  # the last releases, sent as the run returns
        time.sleep(0.05)
    assert not scheduler.tasks


def test_the_local_cluster_slows_dasks_housekeeping(client):
    # The settings are read in the worker processes, which the nannies spawn with the client's configuration.
    def settings():
        import dask
        return {key: dask.config.get(key) for key in streaming.LOCAL_CONFIG}
    for worker, found in client.run(settings).items():
        assert found == streaming.LOCAL_CONFIG, worker
    scheduler = client.cluster.scheduler  # in this process
    assert scheduler._tick_interval == 1.0  # its own event loop check
    assert scheduler.transition_log.maxlen == streaming.LOCAL_CONFIG["distributed.scheduler.transition-log-length"]


def test_a_stopped_run_resumes_to_the_same_bytes(serial_run, tmp_path):
    _, serial_out = serial_run

    def stop_after_the_first_batch(done, total, rate):
        if done < total:
            raise KeyboardInterrupt
    with pytest.raises(jd.Interrupted, match="resume"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path,
                       batch_size=2, progress=stop_after_the_first_batch)
    assert (tmp_path / montecarlo.CHECKPOINT).exists()
    with open(tmp_path / "montecarlo.csv", "ab") as stream:  # rows a killed run wrote after its checkpoint
        stream.write(b"2,0.1,0.2\n" * 2000)
    with pytest.raises(jd.DistributedError, match="--resume"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path)
    with pytest.raises(jd.DistributedError, match="another run"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=8, serial=True, out=tmp_path,
                       resume=True)
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path, resume=True,
                   batch_size=3)
    assert _bytes(tmp_path) == _bytes(serial_out)
    assert not (tmp_path / montecarlo.CHECKPOINT).exists()


def _dask_scratch_folders():
    """This process's cluster folders (jointcomp-dask-<pid>-<start time>-*): other tests that run at the same
    time (ctest -j) make folders of their own in the same temporary root."""
    return set(pathlib.Path(tempfile.gettempdir()).glob("jointcomp-dask-%d-*" % os.getpid()))


def test_ctrl_c_on_a_local_cluster_stops_its_workers_and_removes_its_folder(serial_run, tmp_path):
    """SIGINT to the client (as Ctrl-C gives it) while its own LocalCluster runs: Interrupted with the
    checkpoint, the worker processes ended, the cluster's scratch folder gone, and the checkpoint resumes to
    the uninterrupted run's bytes."""
    import psutil
    _, serial_out = serial_run
    folders_before = _dask_scratch_folders()
    others = psutil.Process().children(recursive=True)  # another cluster's workers (a module fixture's)
    workers, during = [], set()

    def interrupt_at_the_second_batch(done, total, rate):
        during.update(_dask_scratch_folders() - folders_before)
        for child in psutil.Process().children(recursive=True):  # multiprocessing's tracker lives on, by design
            if child not in workers + others and "resource_tracker" not in " ".join(child.cmdline()):
                workers.append(child)
        if done >= 2 and done < total:
            os.kill(os.getpid(), signal.SIGINT)
    with pytest.raises(jd.Interrupted, match="run again with --resume"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, n_workers=2, out=tmp_path,
                       batch_size=1, progress=interrupt_at_the_second_batch)
    assert during and workers  # the run had its folder and its worker processes
    _, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive, "worker processes outlived the run: %s" % [" ".join(p.cmdline()) for p in alive]
    assert not _dask_scratch_folders() - folders_before
    assert (tmp_path / montecarlo.CHECKPOINT).exists()
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path, resume=True)
    assert _bytes(tmp_path) == _bytes(serial_out)


_KILLED_CLIENT = """
import os, signal, sys
from jointcomp import distributed as jd
half = int(sys.argv[4]) // 2
def kill_at_half_way(done, total, rate):
    if done == half:
        print("killed at", done, flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
jd.monte_carlo(sys.argv[1], sys.argv[2], samples=int(sys.argv[4]), seed=7, serial=True, out=sys.argv[3],
               batch_size=1, progress=kill_at_half_way)
"""


def test_a_client_killed_at_half_way_resumes_to_the_same_bytes(serial_run, tmp_path):
    """SIGKILL of the client right after it merged half the draws (no chance to checkpoint on the way out):
    --resume continues from the checkpoint on disk, drops the CSV rows written after it, and ends with the
    bytes of the run never stopped."""
    _, serial_out = serial_run
    child = subprocess.run([sys.executable, "-c", _KILLED_CLIENT, str(RX170_URDF), str(RX170_PARAMETERS),
                            str(tmp_path), str(SAMPLES)], capture_output=True, timeout=120)
    assert child.returncode == -signal.SIGKILL, child.stderr.decode()[-2000:]
    assert child.stdout.decode().split() == ["killed", "at", str(SAMPLES // 2)]
    with np.load(tmp_path / montecarlo.CHECKPOINT) as kept:  # the first batch's: later ones came within 2 s
        assert 1 <= int(kept["draws"]) <= SAMPLES // 2
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path, resume=True)
    assert _bytes(tmp_path) == _bytes(serial_out)
    assert not (tmp_path / montecarlo.CHECKPOINT).exists()


_KILLED_CLUSTER_CLIENT = """
import os, signal, sys
from jointcomp import distributed as jd
def kill_at_the_first_batch(done, total, rate):
    os.kill(os.getpid(), signal.SIGKILL)
jd.monte_carlo(sys.argv[1], sys.argv[2], samples=2, seed=7, n_workers=1, out=sys.argv[3], batch_size=1,
               start_timeout=120, progress=kill_at_the_first_batch)
"""


def test_a_killed_clients_scratch_folders_are_removed_by_the_next_run(tmp_path, monkeypatch):
    """SIGKILL of a client whose LocalCluster works in the temporary root: its folder (with Dask's worker
    space) stays behind, its worker processes end, and the next run, serial or not, removes it; a folder whose
    owner runs and names of another form are kept."""
    import psutil
    from jointcomp import _paths
    root = tmp_path / "tmp"
    root.mkdir()
    child = subprocess.Popen([sys.executable, "-c", _KILLED_CLUSTER_CLIENT, str(RX170_URDF), str(RX170_PARAMETERS),
                              str(tmp_path / "killed")], env=dict(os.environ, TMPDIR=str(root)),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, errors = child.communicate(timeout=120)
    assert child.returncode == -signal.SIGKILL, errors.decode()[-2000:]
    left = list(root.glob("jointcomp-dask-%d-*" % child.pid))
    assert len(left) == 1, sorted(p.name for p in root.iterdir())
    assert list(left[0].rglob("worker-*")), "the killed run's folder has no Dask worker space"

    def in_root(process):
        with contextlib.suppress(psutil.Error):
            return process.environ().get("TMPDIR") == str(root)
        return False
    deadline = time.monotonic() + 20
    while any(in_root(p) for p in psutil.process_iter()) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [p.cmdline() for p in psutil.process_iter() if in_root(p)], "the killed client's workers live on"

    monkeypatch.setattr(tempfile, "tempdir", str(root))
    other_form = root / "jointcomp-dask-handmade"
    other_form.mkdir()
    live = root / ("jointcomp-fleet-%d-%s-x" % (os.getpid(), _paths._start_time(os.getpid())))  # its owner runs
    live.mkdir()
    reused = root / ("jointcomp-dask-%d-1-x" % os.getpid())  # its pid runs, but started at another time
    reused.mkdir()
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=1, seed=7, serial=True, out=tmp_path / "next")
    assert not left[0].exists() and not reused.exists()
    assert live.is_dir() and other_form.is_dir()
    own = "jointcomp-dask-%d-%s-" % (os.getpid(), _paths._start_time(os.getpid()))
    with _paths.scratch_folder("jointcomp-dask-") as made:  # named for this process, removed on leaving
        assert pathlib.Path(made).name.startswith(own)
    assert not pathlib.Path(made).exists() and live.is_dir()


def test_an_interrupt_inside_a_merge_keeps_the_last_checkpoint(serial_run, tmp_path, monkeypatch):
    """Ctrl-C after the summary took a batch but before the CSV got its rows: the stop does not checkpoint
    that half-merged state; the last checkpoint stands and resumes to the same bytes."""
    _, serial_out = serial_run
    rows = montecarlo._csv_rows
    calls = []

    def interrupted_on_the_third_batch(*arguments):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return rows(*arguments)
    monkeypatch.setattr(montecarlo, "_csv_rows", interrupted_on_the_third_batch)
    with pytest.raises(jd.Interrupted, match="1 of 6 draws are kept"):  # the first batch's checkpoint
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path,
                       batch_size=1)
    monkeypatch.setattr(montecarlo, "_csv_rows", rows)
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path, resume=True)
    assert _bytes(tmp_path) == _bytes(serial_out)


def test_a_worker_without_the_library_is_left_out(serial_run, tmp_path, capsys):
    _, serial_out = serial_run
    with jd.cluster(n_workers=2, start_timeout=120) as connected:
        worker = sorted(connected.scheduler_info()["workers"])[0]
        connected.run(exec, "import sys\nfor k in [k for k in sys.modules if k.startswith('jointcomp')]: "
                      "del sys.modules[k]\nsys.modules['jointcomp'] = None", workers=[worker])
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, client=connected, out=tmp_path,
                       batch_size=1)
    assert "worker %s left out" % worker in capsys.readouterr().out
    assert _bytes(tmp_path) == _bytes(serial_out)


def test_a_worker_killed_mid_run_loses_no_draw(serial_run, tmp_path):
    _, serial_out = serial_run
    with jd.cluster(n_workers=2, start_timeout=120) as connected:
        worker = sorted(connected.scheduler_info()["workers"])[0]
        pid = connected.run(os.getpid, workers=[worker])[worker]
        killed = []

        def kill_a_worker_once(done, total, rate):
            if not killed:
                killed.append(worker)
                os.kill(pid, signal.SIGKILL)
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, client=connected, out=tmp_path,
                       batch_size=1, progress=kill_a_worker_once)
        assert worker not in connected.scheduler_info()["workers"]  # it died (its nanny started another)
    assert killed and _bytes(tmp_path) == _bytes(serial_out)


def test_a_lost_scheduler_stops_the_run_with_its_checkpoint(serial_run, tmp_path):
    import distributed
    _, serial_out = serial_run
    other = distributed.LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None, silence_logs=50)
    lost = []

    def lose_the_scheduler(done, total, rate):
        if not lost:
            other.close()
            lost.append(time.monotonic())
    with pytest.raises(jd.DistributedError, match="lost .* run again with --resume"):
        jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, scheduler=other.scheduler_address,
                       out=tmp_path, batch_size=1, progress=lose_the_scheduler)
    # Said at once, not after the client's 30 s of trying to reconnect (nor a cancel waiting for them).
    assert time.monotonic() - lost[0] < 15
    jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=SAMPLES, seed=7, serial=True, out=tmp_path, resume=True)
    assert _bytes(tmp_path) == _bytes(serial_out)


def test_a_scheduler_without_workers_is_named_within_seconds():
    import distributed
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as empty:
        with pytest.raises(jd.DistributedError, match="%s has no worker" % empty.scheduler_address):
            jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, samples=2, seed=7, scheduler=empty.scheduler_address,
                           start_timeout=2)


def test_a_calibration_report_gives_the_law(robot, tmp_path):
    campaign = tmp_path / "campaign.csv"
    jointcomp.simulate_campaign(robot, campaign, protocol="random", count=40, seed=3)
    calibrated, report = jointcomp.calibrate(robot, campaign)
    entries, left = jd.report_distribution(report)
    named = [e["parameter"] for e in entries if "parameter" in e]
    assert named and all(e["law"] == "normal" for e in entries if "parameter" in e)
    assert any(s.startswith(("frame.", "target.")) for s in left)
    with calibrated:
        with jointcomp.SpiralJob(calibrated) as job:
            laws.BoundLaw(entries, job)  # every propagated name is one of the robot's


def test_bad_inputs_are_named(tmp_path):
    def refused(match, **kwargs):
        with pytest.raises(jd.DistributedError, match=match):
            jd.monte_carlo(RX170_URDF, RX170_PARAMETERS, serial=True, **kwargs)
    refused("samples is 0", samples=0)
    refused("seed is -1", seed=-1)
    refused("not a parameter of this robot", samples=1,
            distribution=[{"parameter": "joint_9.stiffness_nm_per_rad", "scale": 1.0}])
    refused("law 'cauchy'", samples=1, distribution=[{"parameter": "joint_2.stiffness_nm_per_rad", "scale": 1.0,
                                                     "law": "cauchy"}])
    for text, match in (("{not json", "is not JSON"), ('[{"parameter": 5, "scale": 1}]', "must be a name"),
                        ('[{"parameter": "a", "scale": "big"}]', "finite number"), ("[]", "non-empty list")):
        path = tmp_path / "law.json"
        path.write_text(text)
        refused(match, samples=1, distribution=str(path))
    for text, match in (('{"format": "jointcomp-calibration-report/1", "parameters": [{"identified": true, '
                         '"sigma": 1}]}', "malformed jointcomp-calibration-report/1 report"),
                        ('{"format": "other"}', "not a report jointcomp knows"), ("[1, 2]", "JSON object")):
        path = tmp_path / "report.json"
        path.write_text(text)
        refused(match, samples=1, report=str(path))


def test_fleet_reports_every_robot_and_writes_the_summary_always(robot, client, tmp_path):
    campaigns = []
    for k in (1, 2):
        path = tmp_path / ("robot%d.csv" % k)
        jointcomp.simulate_campaign(robot, path, protocol="random", count=30, seed=k)
        campaigns.append(path)
    broken = tmp_path / "broken.csv"
    broken.write_text("# not a campaign\n1,2,3\n")
    held = tmp_path / "robot1_again.csv"
    jointcomp.simulate_campaign(robot, held, protocol="random", count=20, seed=9)
    out = tmp_path / "new" / "fleet"  # a folder that does not exist yet
    result = jd.fleet(RX170_URDF, RX170_PARAMETERS, campaigns + [broken], out, client=client,
                      holdouts={str(campaigns[0]): [str(held)]})
    assert [r["name"] for r in result.failed] == ["broken"]
    assert "broken.csv" in result.robots[2]["error"] and "after" in result.robots[0]
    table = (out / "fleet_summary.csv").read_text().splitlines()
    assert table[0].split(",")[8] == "held_out_rms_mm" and float(table[1].split(",")[8]) > 0
    assert "FAILED" in (out / "fleet_summary.txt").read_text()
    assert (out / "robot1" / "calibrated.urdf").exists()
    # Every robot failing still writes the summary, with each reason.
    everything_broken = jd.fleet(RX170_URDF, RX170_PARAMETERS, [broken], tmp_path / "other" / "out", serial=True)
    assert len(everything_broken.failed) == 1
    assert "broken" in (tmp_path / "other" / "out" / "fleet_summary.csv").read_text()


def test_the_outlier_rule():
    robots = [{"name": "r%d" % k, "campaign": "", "before": {"rms_mm": 1.0}, "after": {"rms_mm": v}}
              for k, v in enumerate([0.10, 0.11, 0.09, 0.10, 0.12, 0.50])]
    result = jd.FleetResult("calibrate", robots)
    assert [r["name"] for r in robots if r["outlier"]] == ["r5"]
    assert 0.12 < result.threshold_mm < 0.50


def test_correlated_draws_follow_the_correlation(spiral):
    names = ["joint_2.stiffness_nm_per_rad", "joint_3.stiffness_nm_per_rad"]
    law = jd.check_distribution([{"parameter": names[0], "scale": 1000.0}, {"parameter": names[1], "scale": 1000.0},
                                 {"correlation": {"parameters": names, "matrix": [[1, 0.8], [0.8, 1]]}}])
    bound = laws.BoundLaw(law, spiral)
    draws = np.array([bound.draw(1, k)[0][[spiral.index[n] for n in names]] for k in range(400)])
    assert abs(np.corrcoef(draws.T)[0, 1] - 0.8) < 0.08
    with pytest.raises(jd.DistributedError, match="not a correlation matrix"):
        jd.check_distribution([{"parameter": names[0], "scale": 1.0}, {"parameter": names[1], "scale": 1.0},
                               {"correlation": {"parameters": names, "matrix": [[1, 2], [2, 1]]}}])


def test_forward_kinematics_of_a_batch_is_one_call_per_chunk(robot, monkeypatch):
    rng = np.random.default_rng(2)
    q = rng.uniform(-1, 1, (2500, 6))
    calls = []
    batch = jointcomp._native.lib.jc_forward_kinematics_batch
    monkeypatch.setattr(jointcomp.robot, "_FK_CHUNK", 1000)
    monkeypatch.setattr(jointcomp._native.lib, "jc_forward_kinematics_batch",
                        lambda *a: calls.append(a[1]) or batch(*a))
    poses = robot.forward_kinematics(q)
    assert calls == [1000, 1000, 500]
    monkeypatch.undo()
    for k in (0, 1234, 2499):
        assert np.array_equal(poses[k], robot.forward_kinematics(q[k]))
    assert robot.forward_kinematics(np.empty((0, 6))).shape == (0, 4, 4)
