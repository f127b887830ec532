#!/usr/bin/python3
"""Throughput of jointcomp.distributed's Monte Carlo with 1 and 2 local worker processes (or on a cluster
you name), and the scheduler's overhead per task.

    /usr/bin/python3 bench/dask_bench.py [--samples 16] [--plant] [--scheduler tcp://host:8786]

Run from a checkout with the library built (or set JOINTCOMP_LIBRARY and PYTHONPATH=capi/python). It prints
the draws per second of the serial run (this process, no Dask), of each cluster, and the round trip of a
no-op task, one at a time and in a batch of 500 (the scheduler's cost per task). With --scheduler the
cluster is yours (dask-scheduler on one machine, dask-worker tcp://host:8786 --nthreads 1 on each of the
others, every worker with jointcomp importable and JOINTCOMP_LIBRARY set); without, LocalClusters of 1 and
2 processes are started here.
"""

import argparse
import pathlib
import sys
import time

CHECKOUT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(CHECKOUT / "capi" / "python"))

from jointcomp import distributed as jd  # noqa: E402

URDF = CHECKOUT / "model" / "robots" / "rx170.urdf"
PARAMETERS = CHECKOUT / "model" / "params" / "rx170.json"


def monte_carlo(samples, plant, **where):
    started = time.perf_counter()
    jd.monte_carlo(URDF, PARAMETERS, samples=samples, seed=1, use_plant=plant, **where)
    return time.perf_counter() - started


def overhead(client):
    """Seconds per no-op task: one at a time (latency), then 500 submitted together (throughput)."""
    client.submit(jd._no_op, 0, pure=False).result()  # warm
    started = time.perf_counter()
    for k in range(50):
        client.submit(jd._no_op, k, pure=False).result()
    latency = (time.perf_counter() - started) / 50
    started = time.perf_counter()
    futures = [client.submit(jd._no_op, k, pure=False) for k in range(500)]
    client.gather(futures)
    batch = (time.perf_counter() - started) / 500
    return latency, batch


def on_cluster(label, samples, plant, **where):
    started = time.perf_counter()
    with jd.cluster(start_timeout=120, **where) as client:
        start = time.perf_counter() - started
        workers = len(client.scheduler_info()["workers"])
        monte_carlo(min(samples, 2 * workers), plant, client=client)  # warm: every worker loads the library
        seconds = monte_carlo(samples, plant, client=client)
        latency, batch = overhead(client)
    print("%-24s %3d workers  %7.2f draws/s  (%d draws in %.2f s; cluster start %.1f s)" % (
        label, workers, samples / seconds, samples, seconds, start))
    print("%-24s no-op task: %.2f ms one at a time, %.2f ms each in a batch of 500" % (
        "", latency * 1e3, batch * 1e3))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--plant", action="store_true", help="the flexible-joint plant (about 2.5 x slower)")
    parser.add_argument("--scheduler", help="a running cluster's scheduler, e.g. tcp://host:8786")
    arguments = parser.parse_args()
    print("Monte Carlo of the RX170 spiral, %s robot, %d draws" % (
        "flexible-joint plant" if arguments.plant else "quasi-static", arguments.samples))
    seconds = monte_carlo(arguments.samples, arguments.plant, serial=True)
    print("%-24s %3s workers  %7.2f draws/s  (%d draws in %.2f s)" % (
        "serial (this process)", "-", arguments.samples / seconds, arguments.samples, seconds))
    if arguments.scheduler:
        on_cluster(arguments.scheduler, arguments.samples, arguments.plant, scheduler=arguments.scheduler)
    else:
        for n in (1, 2):
            on_cluster("LocalCluster", arguments.samples, arguments.plant, n_workers=n)


if __name__ == "__main__":
    main()
