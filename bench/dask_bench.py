#!/usr/bin/python3
"""jointcomp.distributed's Monte Carlo: the cost of a draw against its compensations, the speed-up of a
LocalCluster over the serial run, and the memory of a long streamed run.

    /usr/bin/python3 bench/dask_bench.py [--samples 200] [--workers 2] [--long 100000] [--plant]
                                         [--scheduler tcp://host:8786]

Run from a checkout with the library built (or set JOINTCOMP_LIBRARY and PYTHONPATH=capi/python). It prints
1. the seconds of one draw (jointcomp.SpiralJob.run: the truth's three runs and the tracker) and of the
   three compensations of the spiral it follows (Robot.compensate_trajectory), and their ratio;
2. draws per second serial (this process) and on a LocalCluster of --workers processes (or --scheduler),
   and the speed-up;
3. with --long N: a run of N draws on the cluster, sampling every second the client's resident memory (the
   LocalCluster's scheduler runs in the client process) and the workers'; the peak and the first and last
   thirds' means say whether memory stays flat.
"""

import argparse
import pathlib
import sys
import tempfile
import threading
import time

CHECKOUT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(CHECKOUT / "capi" / "python"))

import psutil  # noqa: E402 (a dependency of Dask's distributed)

import jointcomp  # noqa: E402
from jointcomp import distributed as jd  # noqa: E402

URDF = CHECKOUT / "model" / "robots" / "rx170.urdf"
PARAMETERS = CHECKOUT / "model" / "params" / "rx170.json"


def draw_against_compensations(plant, repeats=5):
    with jointcomp.Robot(URDF, PARAMETERS) as robot:
        with jointcomp.SpiralJob(robot, plant) as job:
            law = jd.laws.BoundLaw(jd.main_job_distribution(job), job)
            values, seed, _ = law.draw(1, 0)
            job.run(values, seed)
            started = time.perf_counter()
            for k in range(repeats):
                job.run(*law.draw(1, k)[:2])
            draw = (time.perf_counter() - started) / repeats
        plan = robot.spiral_plan()
        started = time.perf_counter()
        for _ in range(repeats):
            for effects in ("", "compliance", "compliance,transmission_error"):
                robot.compensate_trajectory(plan.q, plan.qd, effects=effects)
        compensations = (time.perf_counter() - started) / repeats
    print("one draw %.1f ms; its three compensations %.1f ms (%d samples each); ratio %.2f" % (
        draw * 1e3, compensations * 1e3, len(plan.time), draw / compensations))


def throughput(samples, plant, where):
    started = time.perf_counter()
    jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, **where)
    return samples / (time.perf_counter() - started)


class MemorySampler(threading.Thread):
    """Resident memory of this process and of its children (the workers), every second."""

    def __init__(self):
        super().__init__(daemon=True)
        self.client, self.workers, self.running = [], [], True

    def run(self):
        me = psutil.Process()
        while self.running:
            self.client.append(me.memory_info().rss)
            self.workers.append(sum(c.memory_info().rss for c in me.children(recursive=True)))
            time.sleep(1.0)

    def report(self, label, values):
        third = max(1, len(values) // 3)
        print("%s RSS: peak %.0f MB; mean of the first third %.0f MB, of the last third %.0f MB" % (
            label, max(values) / 2**20, sum(values[:third]) / third / 2**20, sum(values[-third:]) / third / 2**20))


def long_run(samples, plant, where):
    sampler = MemorySampler()
    sampler.start()
    with tempfile.TemporaryDirectory(prefix="jointcomp-bench-") as out:
        started = time.perf_counter()
        result = jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, out=out,
                                progress=jd.console_progress(every=30.0), **where)
        seconds = time.perf_counter() - started
        csv_mb = pathlib.Path(out, "montecarlo.csv").stat().st_size / 2**20
    sampler.running = False
    print("%d draws in %.0f s (%.1f draws/s), %d failed; montecarlo.csv %.1f MB" % (
        samples, seconds, samples / seconds, len(result.failed), csv_mb))
    sampler.report("client (and the LocalCluster's scheduler)", sampler.client)
    sampler.report("workers (together)", sampler.workers)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=200, help="draws of the throughput runs")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--long", type=int, default=0, help="draws of the memory run (0: none)")
    parser.add_argument("--plant", action="store_true", help="the flexible-joint plant")
    parser.add_argument("--scheduler", help="a running cluster's scheduler, e.g. tcp://host:8786")
    arguments = parser.parse_args()
    print("Monte Carlo of the RX170 spiral, %s robot" % ("flexible-joint plant" if arguments.plant else "quasi-static"))
    draw_against_compensations(arguments.plant)
    serial = throughput(arguments.samples, arguments.plant, {"serial": True})
    where = {"scheduler": arguments.scheduler} if arguments.scheduler else {"n_workers": arguments.workers}
    with jd.cluster(start_timeout=120, **where) as client:
        workers = len(client.scheduler_info()["workers"])
        throughput(2 * workers, arguments.plant, {"client": client})  # warm: every worker prepares the job
        parallel = throughput(arguments.samples, arguments.plant, {"client": client})
        print("%d draws: serial %.1f draws/s; %d workers %.1f draws/s; speed-up %.2f" % (
            arguments.samples, serial, workers, parallel, parallel / serial))
        if arguments.long:
            long_run(arguments.long, arguments.plant, {"client": client})


if __name__ == "__main__":
    main()
