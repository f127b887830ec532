#!/usr/bin/python3
"""jointcomp.distributed's Monte Carlo: the cost of a draw against its compensations, the speed-up of a
LocalCluster over the serial run, and the memory of a long streamed run.

    /usr/bin/python3 bench/dask_bench.py [--samples 400] [--workers 2] [--long 100000] [--plant]
                                         [--memory-log FILE] [--sample-every 10] [--scheduler tcp://host:8786]

Run from a checkout with the library built (or set JOINTCOMP_LIBRARY and PYTHONPATH=capi/python). It prints
1. the seconds of one draw (jointcomp.SpiralJob.run: the truth's three runs and the tracker) and of the
   three compensations of the spiral it follows (Robot.compensate_trajectory), and their ratio;
2. draws per second serial (this process) and on a LocalCluster of --workers processes (or --scheduler),
   the wall-clock speed-up and the load average it was measured at; for a LocalCluster also the CPU an idle
   cluster burns a second, the CPU each draw costs serial, in the workers and in the client (which hosts
   the scheduler and the nannies), and the speed-up they allow on idle cores: on a loaded machine the
   kernel shares the cores between sessions, and the wall clock says little;
3. with --long N: a run of N draws on the cluster, sampling every --sample-every s the resident memory of
   the client (the LocalCluster's scheduler runs in the client process), of each worker, the scheduler's
   task count and transition log, and the draws done, into --memory-log (tab-separated) and the console's
   summary: start, middle and end, and whether memory stays flat.
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
    LocalCluster's scheduler and nannies) and of its children (the LocalCluster's workers)."""
    me = psutil.Process()
    children = me.children(recursive=True)
    client, workers = _cpu_seconds([me]), _cpu_seconds(children)
    started = time.perf_counter()
    jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, **where)
    rate = samples / (time.perf_counter() - started)
    return rate, (_cpu_seconds([me]) - client) / samples, (_cpu_seconds(children) - workers) / samples


def idle_cpu(seconds=5.0):
    """CPU seconds a second of this process and of its children while the cluster has nothing to do:
    Dask's housekeeping (heartbeats, event-loop checks, monitors), paid per second whatever the draws."""
    me = psutil.Process()
    children = me.children(recursive=True)
    client, workers = _cpu_seconds([me]), _cpu_seconds(children)
    time.sleep(seconds)
    return (_cpu_seconds([me]) - client) / seconds, (_cpu_seconds(children) - workers) / seconds


class MemorySampler(threading.Thread):
    """Every ``every`` s: resident memory of this process (the client, with a LocalCluster's scheduler) and
    of each child (the workers), the scheduler's tasks and transition log when it runs here, and the draws
    done; appended to ``log`` (tab-separated) when given."""

    def __init__(self, every, log, scheduler=None):
        super().__init__(daemon=True)
        self.every, self.log, self.scheduler = every, log, scheduler
        self.rows, self.done, self.stop = [], 0, threading.Event()
        self.started = time.monotonic()

    def progress(self, done, total, rate):
        self.done = done

    def sample(self):
        me = psutil.Process()
        workers = []
        for child in me.children(recursive=True):
            try:
                if "spawn_main" in " ".join(child.cmdline()):
                    workers.append(child.memory_info().rss / 2**20)
            except psutil.NoSuchProcess:
                pass
        tasks = log = -1
        if self.scheduler is not None:
            tasks, log = len(self.scheduler.tasks), len(self.scheduler.transition_log)
        row = (time.monotonic() - self.started, self.done, me.memory_info().rss / 2**20, tasks, log,
               os.getloadavg()[0], workers)
        self.rows.append(row)
        if self.log:
            with open(self.log, "a", encoding="utf-8") as stream:
                stream.write("%.0f\t%d\t%.1f\t%d\t%d\t%.1f\t%s\n" % (
                    row[:6] + ("\t".join("%.1f" % w for w in workers),)))

    def run(self):
        if self.log:
            with open(self.log, "w", encoding="utf-8") as stream:
                stream.write("seconds\tdraws\tclient_rss_mb\tscheduler_tasks\tscheduler_transition_log\t"
                             "load_average\tworker_rss_mb...\n")
        while not self.stop.is_set():
            self.sample()
            self.stop.wait(self.every)

    def report(self):
        self.sample()
        rows = self.rows
        for label, row in (("start", rows[min(1, len(rows) - 1)]), ("middle", rows[len(rows) // 2]), ("end", rows[-1])):
            print("%-6s %6.0f s %7d draws: client RSS %.0f MB (with the scheduler: %d tasks, transition log %d); "
                  "workers %s MB; load %.1f" % (label, row[0], row[1], row[2], row[3], row[4],
                                               " + ".join("%.0f" % w for w in row[6]), row[5]))
        client = [r[2] for r in rows]
        print("client RSS: peak %.0f MB" % max(client))


def long_run(samples, plant, where, every, log):
    scheduler = getattr(getattr(where["client"], "cluster", None), "scheduler", None)
    sampler = MemorySampler(every, log, scheduler)
    sampler.start()
    report = jd.console_progress(every=60.0)

    def progress(done, total, rate):
        sampler.progress(done, total, rate)
        report(done, total, rate)
    me = psutil.Process()
    children = me.children(recursive=True)
    client, workers = _cpu_seconds([me]), _cpu_seconds(children)
    with tempfile.TemporaryDirectory(prefix="jointcomp-bench-") as out:
        started = time.perf_counter()
        result = jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, out=out,
                                progress=progress, timeout=7 * 86400.0, **where)
        seconds = time.perf_counter() - started
        csv_mb = pathlib.Path(out, "montecarlo.csv").stat().st_size / 2**20
    sampler.stop.set()
    sampler.join()
    print("%d draws in %.0f s (%.1f draws/s, load average %.1f), %d failed; montecarlo.csv %.1f MB" % (
        samples, seconds, samples / seconds, os.getloadavg()[0], len(result.failed), csv_mb))
    print("CPU per draw: %.2f ms in the workers, %.2f ms in the client (with the scheduler and the nannies)" % (
        (_cpu_seconds(children) - workers) / samples * 1e3, (_cpu_seconds([me]) - client) / samples * 1e3))
    sampler.report()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=400, help="draws of the throughput runs")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--long", type=int, default=0, help="draws of the memory run (0: none)")
    parser.add_argument("--memory-log", help="file the memory run's samples go to")
    parser.add_argument("--sample-every", type=float, default=10.0, help="seconds between memory samples")
    parser.add_argument("--plant", action="store_true", help="the flexible-joint plant")
    parser.add_argument("--scheduler", help="a running cluster's scheduler, e.g. tcp://host:8786")
    arguments = parser.parse_args()
    print("Monte Carlo of the RX170 spiral, %s robot" % ("flexible-joint plant" if arguments.plant else "quasi-static"))
    if arguments.samples:
        draw_against_compensations(arguments.plant)
        serial, serial_cpu, _ = throughput(arguments.samples, arguments.plant, {"serial": True})
    where = {"scheduler": arguments.scheduler} if arguments.scheduler else {"n_workers": arguments.workers}
    with jd.cluster(start_timeout=120, **where) as client:
        if arguments.samples:
            speed_up(client, arguments, serial, serial_cpu)
        if arguments.long:
            long_run(arguments.long, arguments.plant, {"client": client}, arguments.sample_every,
                     arguments.memory_log)


def speed_up(client, arguments, serial, serial_cpu):
    workers = len(client.scheduler_info()["workers"])
    throughput(2 * workers, arguments.plant, {"client": client})  # warm: every worker prepares the job
    if not arguments.scheduler:
        idle_client, idle_workers = idle_cpu()
        print("idle cluster: %.1f ms of CPU a second in the client (scheduler, nannies), %.1f in the workers" % (
            idle_client * 1e3, idle_workers * 1e3))
    parallel, client_cpu, workers_cpu = throughput(arguments.samples, arguments.plant, {"client": client})
    print("%d draws, wall clock: serial %.1f draws/s; %d workers %.1f draws/s; speed-up %.2f (load average %.1f "
          "on %d cores)" % (arguments.samples, serial, workers, parallel, parallel / serial, os.getloadavg()[0],
                            os.cpu_count() or 1))
    if not arguments.scheduler:
        # A loaded machine shares its cores between sessions (the kernel's autogroups), not processes: the
        # wall-clock speed-up then says little. The CPU each draw costs does not depend on the load: with
        # every core of this machine free, a draw takes (workers' CPU + client's CPU) / cores at best.
        cores = min(workers, os.cpu_count() or 1)
        print("CPU per draw: serial %.2f ms; cluster %.2f ms in the workers + %.2f ms in the client; on %d idle "
              "cores a speed-up of at most %.2f (%.2f with the client and scheduler on another machine)" % (
                  serial_cpu * 1e3, workers_cpu * 1e3, client_cpu * 1e3, cores,
                  cores * serial_cpu / (workers_cpu + client_cpu), cores * serial_cpu / workers_cpu))


if __name__ == "__main__":
    main()
