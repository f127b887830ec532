#!/usr/bin/python3
"""jointcomp.distributed's Monte Carlo: the cost of a draw against its compensations, the speed-up of a
LocalCluster over the serial run, and the memory of a long streamed run.

    /usr/bin/python3 bench/dask_bench.py [--samples 200] [--workers 2] [--long 100000] [--plant]
                                         [--scheduler tcp://host:8786]

Run from a checkout with the library built (or set JOINTCOMP_LIBRARY and PYTHONPATH=capi/python). It prints
1. the seconds of one draw (jointcomp.SpiralJob.run: the truth's three runs and the tracker) and of the
   three compensations of the spiral it follows (Robot.compensate_trajectory), and their ratio;
2. draws per second serial (this process) and on a LocalCluster of --workers processes (or --scheduler),
   and the speed-up; for a LocalCluster also the CPU each draw costs serial, in the workers and in the client
   (with the scheduler), and the speed-up they allow on idle cores (a loaded machine's wall clock cannot say);
3. with --long N: a run of N draws on the cluster, sampling every second the client's resident memory (the
   LocalCluster's scheduler runs in the client process) and the workers'; the peak and the first and last
   thirds' means say whether memory stays flat.
"""

import argparse
import os
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


def _cpu_seconds(processes):
    total = 0.0
    for process in processes:
        try:
            times = process.cpu_times()
            total += times.user + times.system
        except psutil.NoSuchProcess:
            pass
    return total


def throughput(samples, plant, where):
    """Draws per second (wall clock), and the CPU seconds per draw of this process (the client, and a
    LocalCluster's scheduler) and of its children (the LocalCluster's workers and nannies)."""
    me = psutil.Process()
    children = me.children(recursive=True)
    client, workers = _cpu_seconds([me]), _cpu_seconds(children)
    started = time.perf_counter()
    jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, **where)
    rate = samples / (time.perf_counter() - started)
    return rate, (_cpu_seconds([me]) - client) / samples, (_cpu_seconds(children) - workers) / samples


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
    serial, serial_cpu, _ = throughput(arguments.samples, arguments.plant, {"serial": True})
    where = {"scheduler": arguments.scheduler} if arguments.scheduler else {"n_workers": arguments.workers}
    with jd.cluster(start_timeout=120, **where) as client:
        workers = len(client.scheduler_info()["workers"])
        throughput(2 * workers, arguments.plant, {"client": client})  # warm: every worker prepares the job
        parallel, client_cpu, workers_cpu = throughput(arguments.samples, arguments.plant, {"client": client})
        print("%d draws: serial %.1f draws/s; %d workers %.1f draws/s; speed-up %.2f (load average %.1f)" % (
            arguments.samples, serial, workers, parallel, parallel / serial, os.getloadavg()[0]))
        if not arguments.scheduler:
            # A loaded machine shares its cores between sessions (the kernel's autogroups), not processes: the
            # wall-clock speed-up then says little. The CPU each draw costs does not depend on the load: with
            # every core of this machine free, a draw takes (workers' CPU + client's CPU) / cores at best.
            cores = os.cpu_count() or 1
            print("CPU per draw: serial %.1f ms; cluster %.1f ms in the workers + %.1f ms in the client; on %d idle "
                  "cores a speed-up of at most %.2f" % (
                      serial_cpu * 1e3, workers_cpu * 1e3, client_cpu * 1e3, cores,
                      min(workers, cores) * serial_cpu / (workers_cpu + client_cpu)))
        if arguments.long:
            long_run(arguments.long, arguments.plant, {"client": client})


if __name__ == "__main__":
    main()
