"""Monte Carlo accuracy of the spiral under parameter uncertainty, streamed in batches over a Dask cluster.

Each task is a batch of consecutive draws. The worker keeps one jointcomp.SpiralJob per job (the spiral
planned and compensated once with the nominal parameters), draws each truth from the draw's own generator
(laws.py: SeedSequence([seed, k])), follows the prepared runs with it in one C call, and reduces the batch
to a mergeable Summary (summary.py) and the batch's per-draw metrics. The client merges the batches in draw
order, appends the metrics to montecarlo.csv, and checkpoints the merged summary, so that its memory does
not depend on the number of draws and a run stopped anywhere resumes to the same bytes.
"""

import hashlib
import json
import math
import os
import pathlib
import sys
import time

import numpy as np

from .._paths import prepare_output_folder, remove_stale_scratch_folders, write_atomically
from . import streaming as _cluster
from .laws import (BoundLaw, DistributedError, check_distribution, load_distribution, main_job_distribution,
                   report_distribution)
from .results import MonteCarloResult
from .summary import Summary

DEFAULT_SEED = 2019
MAX_SAMPLES = 10_000_000  # jointcomp montecarlo's cap too: the CSV then holds about 1.5 GB
BATCH_SECONDS = 2.0       # a batch's work, from the measured cost of a draw
CHECKPOINT = "montecarlo.checkpoint.npz"
CSV_NAME = "montecarlo.csv"
FORMAT = "jointcomp-montecarlo/3"  # of the checkpoint (/3: its counts sparse)


class Interrupted(DistributedError):
    """A run stopped by Ctrl-C (or SIGTERM); the checkpoint keeps what was done."""


# ---- The task: runs on the workers, plain data in, a summary out ------------------------------------------

_PREPARED = {}  # per worker process: job key -> (SpiralJob, BoundLaw, band indices), the last job only


def _prepared(job):
    """The worker's SpiralJob and bound law of ``job``, made once per process (planning and the three
    compensations are the same for every draw)."""
    if job["key"] not in _PREPARED:
        jointcomp = _cluster.load_jointcomp()
        _PREPARED.clear()
        with jointcomp.Robot.from_text(job["urdf_text"], job["parameters_json"]) as nominal:
            spiral = jointcomp.SpiralJob(nominal, job["use_plant"])
        law = BoundLaw(job["distribution"], spiral)
        band = np.unique(np.linspace(0, spiral.samples - 1, job["band_points"]).round().astype(np.int64))
        _PREPARED[job["key"]] = (spiral, law, band)
    return _PREPARED[job["key"]]


def _batch_task(job, batch):
    """Draws ``batch`` = (first, stop) of ``job``: {"summary": Summary, "metrics": (count, 3, 5) in m, NaN for
    a failed draw}."""
    from ..errors import JointcompError
    spiral, law, band = _prepared(job)
    first, stop = batch
    summary = Summary(len(band))
    metrics = np.full((stop - first, 3, 5), np.nan)
    errors = np.empty((3, spiral.samples, 3))
    for k in range(first, stop):
        values, noise_seed, clamped = law.draw(job["seed"], k)
        summary.clamped += clamped
        try:
            metrics[k - first] = spiral.run(values, noise_seed, errors)
        except JointcompError as error:
            summary.add_failure(k, "%s: %s" % (type(error).__name__, error))
            continue
        at_band = errors[:, band, :]
        summary.add_draw(metrics[k - first], at_band[:, :, 2], np.linalg.norm(at_band, axis=2))
    return {"summary": summary, "metrics": metrics}


# ---- The client ---------------------------------------------------------------------------------------------

def _read_text(path, name):
    path = pathlib.Path(path)
    if not path.is_file():
        raise DistributedError("%s: %s does not exist or is not a file" % (name, path))
    return path.read_text(encoding="utf-8")


def _parameters_text(parameters):
    text = str(parameters)
    return text if text.lstrip().startswith("{") else _read_text(parameters, "parameters")


def _law(report, distribution, spiral):
    """(entries, not_propagated): the report's law, the distribution's, or the main job's."""
    if report is not None:
        return report_distribution(report)
    if distribution is not None:
        if isinstance(distribution, (str, os.PathLike)):
            return load_distribution(distribution), []
        return check_distribution(distribution), []
    entries = main_job_distribution(spiral)
    if not entries:
        raise DistributedError("parameters: no effect parameter the main job perturbs; give a report or a "
                               "distribution")
    return entries, []


def _fingerprint(job, samples):
    """What a checkpoint must match to be resumed: every input of the results."""
    text = json.dumps([FORMAT, job["urdf_text"], job["parameters_json"], job["distribution"], job["seed"],
                       job["use_plant"], job["band_points"], samples], sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _prepare_job(urdf, parameters, seed, report, distribution, use_plant, band_points):
    """The job every task carries (file contents, not paths), the client's own SpiralJob checks, and the
    measured seconds of one draw (the batch size follows from it)."""
    import jointcomp
    urdf_text = _read_text(urdf, "urdf")
    parameters_json = _parameters_text(parameters)
    with jointcomp.Robot.from_text(urdf_text, parameters_json) as nominal:
        if use_plant and not nominal.has_drives:
            raise DistributedError("use_plant: the parameters have no \"plant\" object (drives)")
        spiral = jointcomp.SpiralJob(nominal, use_plant)
    with spiral:
        entries, not_propagated = _law(report, distribution, spiral)
        law = BoundLaw(entries, spiral)  # every name checked here, before any worker starts
        values, noise_seed, _ = law.draw(seed, 0)
        started = time.perf_counter()
        try:
            spiral.run(values, noise_seed)
        except jointcomp.JointcompError:
            pass  # a draw that fails is the run's to report, not a reason to refuse it
        seconds = time.perf_counter() - started
        time_points = spiral.time()
    band = np.unique(np.linspace(0, len(time_points) - 1, band_points).round().astype(np.int64))
    job = {"urdf_text": urdf_text, "parameters_json": parameters_json, "distribution": entries, "seed": seed,
           "use_plant": bool(use_plant), "band_points": int(band_points)}
    return job, not_propagated, seconds, time_points[band]


def _batches(first, samples, size):
    return [(k, min(k + size, samples)) for k in range(first, samples, size)]


class _Run:
    """The client's side of a run: the merged summary, the CSV, the checkpoint and the progress."""

    def __init__(self, job, samples, out, resume, progress):
        self.job, self.samples, self.out, self.progress = job, samples, out, progress
        self.summary = Summary(job["band_points"])
        self.csv = None
        self.started = time.monotonic()
        self.saved = self.started
        self.first = 0
        self.merging = False
        self.kept = None  # the draws the checkpoint on disk holds (None: no checkpoint written yet)
        if out is not None:
            self._open(resume)

    def _open(self, resume):
        checkpoint = self.out / CHECKPOINT
        if resume and checkpoint.exists():
            with np.load(checkpoint, allow_pickle=False) as stored:
                if str(stored["fingerprint"]) != self.job["run"]:
                    raise DistributedError("--resume: %s is of another run (other inputs, seed or samples)" % checkpoint)
                self.summary = Summary.from_arrays(stored, json.loads(str(stored["failed"])))
                csv_bytes = int(stored["csv_bytes"])
            self.first = self.kept = self.summary.draws
            self.csv = open(self.out / CSV_NAME, "r+b")
            self.csv.truncate(csv_bytes)
            self.csv.seek(csv_bytes)
            return
        if resume:
            raise DistributedError("--resume: %s has no checkpoint (%s) to resume from" % (self.out, CHECKPOINT))
        if checkpoint.exists():
            raise DistributedError("%s holds the checkpoint of an unfinished run: add --resume to continue it, or "
                                   "remove %s" % (self.out, checkpoint))
        self.csv = open(self.out / CSV_NAME, "wb")
        header = ["draw"] + ["%s_%s_mm" % (r, m) for r in ("uncompensated", "stiffness", "compensated")
                             for m in ("ra", "rz", "rms", "max")] + ["error"]
        self.csv.write((",".join(header) + "\n").encode("utf-8"))

    def merge(self, batch, result):
        # A Ctrl-C between the summary's merge and the CSV's rows would leave the two disagreeing: until both
        # are done, a stop keeps the last checkpoint written instead of writing this state (see _stopped).
        self.merging = True
        self.summary.merge(result["summary"])
        if self.csv is not None:
            self.csv.write(_csv_rows(batch, result["metrics"], result["summary"].failed).encode("utf-8"))
        self.merging = False
        now = time.monotonic()
        if self.out is not None and (now - self.saved >= 2.0 or self.saved == self.started):
            self.checkpoint()  # the first batch at once, then every 2 s
        if self.progress is not None:
            done = self.summary.draws
            rate = (done - self.first) / max(now - self.started, 1e-9)
            self.progress(done, self.samples, rate)

    def checkpoint(self):
        """The merged summary and the CSV's length, whole or not at all."""
        if self.out is None:
            return
        self.csv.flush()
        os.fsync(self.csv.fileno())
        arrays = dict(self.summary.arrays(), fingerprint=np.array(self.job["run"]),
                      failed=np.array(json.dumps(sorted(self.summary.failed.items()))),
                      csv_bytes=np.int64(self.csv.tell()))
        write_atomically(self.out / CHECKPOINT, lambda stream: np.savez(stream, **arrays))
        self.saved = time.monotonic()
        self.kept = self.summary.draws

    def close(self):
        if self.csv is not None:
            self.csv.close()
            self.csv = None


def _csv_rows(batch, metrics, failed):
    lines = []
    for i, k in enumerate(range(*batch)):
        cells = ["%.9g" % (metrics[i, r, m] * 1e3) for r in range(3) for m in range(4)]
        message = failed.get(k, "").replace('"', "'").replace("\n", " ")
        lines.append("%d,%s,%s\n" % (k, ",".join(cells), '"%s"' % message if message else ""))
    return "".join(lines)


def console_progress(stream=None, every=5.0):
    """A progress callback printing draws done, rate and time left to ``stream`` (stderr) every ``every`` s."""
    last = [0.0]

    def show(done, total, rate):
        now = time.monotonic()
        if now - last[0] < every and done < total:
            return
        last[0] = now
        left = (total - done) / rate if rate > 0 else float("inf")
        print("montecarlo: %d / %d draws (%.1f %%), %.1f draws/s, %s left" % (
            done, total, 100.0 * done / total, rate, _duration(left)), file=stream or sys.stderr, flush=True)
    return show


def _duration(seconds):
    if not math.isfinite(seconds):
        return "unknown time"
    if seconds < 90:
        return "%.0f s" % seconds
    if seconds < 5400:
        return "%.0f min" % (seconds / 60)
    return "%.1f h" % (seconds / 3600)


def _check_arguments(samples, seed, band_points):
    if not isinstance(samples, int) or isinstance(samples, bool) or not 1 <= samples <= MAX_SAMPLES:
        raise DistributedError("samples is %r, must be an integer from 1 to %d" % (samples, MAX_SAMPLES))
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise DistributedError("seed is %r, must be an integer >= 0" % (seed,))
    if not isinstance(band_points, int) or not 2 <= band_points <= 5000:
        raise DistributedError("band_points is %r, must be an integer from 2 to 5000" % (band_points,))


def monte_carlo(urdf, parameters, *, samples=100, seed=DEFAULT_SEED, report=None, distribution=None,
                use_plant=False, out=None, resume=False, progress=None, client=None, scheduler=None, n_workers=None,
                serial=False, timeout=3600.0, start_timeout=30.0, retries=2, band_points=300, batch_size=None,
                dashboard=None):
    """Monte Carlo of the spiral under parameter uncertainty; returns a :class:`MonteCarloResult`.

    ``urdf``: the robot's URDF path; ``parameters``: its (nominal, identified) parameter file path, or the
    JSON text. The law: ``report`` (a report or its report.json, see laws.report_distribution), else
    ``distribution`` (a list of entries or a JSON file, see laws), else the main job's perturbation as the
    library states it. ``samples`` draws of ``seed``. ``use_plant``: the flexible-joint plant (needs drives)
    instead of the quasi-static robot. ``out``: a folder for montecarlo.json, montecarlo.csv (one row per
    draw, streamed), montecarlo_band.png and, while running, the checkpoint; ``resume``: continue the run
    whose checkpoint is in ``out`` (the same bytes as a run never stopped). ``progress(done, total,
    draws_per_second)`` is called as batches are merged. Where: ``client``, ``scheduler`` (an address), a
    LocalCluster of ``n_workers`` processes (``dashboard``: its address, none by default), or
    ``serial=True`` for this process only (the same results). ``timeout``: seconds for all draws;
    ``retries``: reruns of a task whose worker died; ``batch_size``: draws per task (default: about
    BATCH_SECONDS of work each).
    """
    _check_arguments(samples, seed, band_points)
    if out is not None:
        out = prepare_output_folder(out, DistributedError, "out")
    remove_stale_scratch_folders()  # what killed runs left, whether this one runs on a cluster or not
    job, not_propagated, seconds, band_time = _prepare_job(urdf, parameters, seed, report, distribution,
                                                           use_plant, band_points)
    job["key"] = _fingerprint(job, None)  # what the workers' prepared job depends on (not the number of draws)
    job["run"] = _fingerprint(job, samples)  # what a checkpoint must match
    run = _Run(job, samples, out, resume, progress)
    workers = 1 if serial else max(1, n_workers or os.cpu_count() or 1)
    size = batch_size or max(1, min(1000, int(BATCH_SECONDS / max(seconds, 1e-4)),
                                   -(-samples // (4 * workers))))
    batches = _batches(run.first, samples, size)
    try:
        if serial:
            _cluster.stream(None, _batch_task, job, batches, run.merge, in_flight=1, timeout=timeout,
                            retries=retries, describe="monte carlo")
        else:
            with _cluster.cluster(client, scheduler, n_workers, start_timeout, dashboard) as connected:
                in_flight = 2 * max(1, len(connected.scheduler_info().get("workers", {})))
                _cluster.stream(connected, _batch_task, job, batches, run.merge, in_flight=in_flight,
                                timeout=timeout, retries=retries, describe="monte carlo", scheduler=scheduler)
    except KeyboardInterrupt:
        raise _stopped(run, Interrupted, "interrupted") from None
    except DistributedError as error:
        raise _stopped(run, DistributedError, str(error)) from None
    result = MonteCarloResult(run.summary, job, samples, not_propagated, band_time)
    if out is not None:
        run.close()
        result.write(out)
        (out / CHECKPOINT).unlink(missing_ok=True)
    return result


def _stopped(run, kind, what):
    """The error of a run that stops part-way, its checkpoint written first when there is one."""
    done = run.summary.draws
    if run.out is None:
        run.close()
        return kind("%s: %d of %d draws were done (give out= to keep a checkpoint)" % (what, done, run.samples))
    if not run.merging:
        run.checkpoint()
    elif run.kept is not None:
        done = run.kept  # stopped inside a merge: the last checkpoint stands (resume truncates the CSV to it)
    else:
        run.close()
        return kind("%s before the first batch was kept: run again without --resume" % what)
    run.close()
    return kind("%s; %d of %d draws are kept in %s: run again with --resume (resume=True) to continue" % (
        what, done, run.samples, run.out / CHECKPOINT))
