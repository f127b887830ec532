"""The Dask side: a cluster to run on, and tasks streamed through it with a bounded number in flight.

Failures say what happened: a scheduler without workers is an error within ``start_timeout`` naming it; a
worker that cannot load the library is left out and its task runs elsewhere; a lost scheduler or Ctrl-C
stop the run with the number of tasks done (the caller's checkpoint keeps them); a LocalCluster started here
works in a temporary folder removed on leaving (or by the next run, when it was killed), and serves no
dashboard unless asked.
"""

import contextlib
import os
import pathlib
import queue
import signal
import threading
import time

from .._paths import scratch_folder
from .laws import DistributedError


LOST_AFTER = 10.0  # s without a connection to the scheduler before the run is called lost


class WorkerWithoutLibrary(Exception):
    """Raised by a task on a worker that cannot import jointcomp or load libjointcomp: args are the worker's
    address (None outside a worker) and why."""


def load_jointcomp():
    """jointcomp on a worker, or WorkerWithoutLibrary saying why not and which worker."""
    try:
        import jointcomp
    except Exception as error:  # ImportError, OSError from ctypes: this worker cannot run tasks
        address = None
        with contextlib.suppress(Exception):
            from distributed import get_worker
            address = get_worker().address
        raise WorkerWithoutLibrary(address, "%s: %s" % (type(error).__name__, error)) from None
    return jointcomp


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise DistributedError("Dask's distributed package is missing: apt-get install python3-distributed "
                               "python3-dask (packaging/install-deps.sh)") from None
    return distributed


@contextlib.contextmanager
def cluster(client=None, scheduler=None, n_workers=None, start_timeout=30.0, dashboard=None):
    """A Dask client: ``client`` as given, one connected to ``scheduler`` (an address such as
    tcp://host:8786), or a LocalCluster of ``n_workers`` single-threaded worker processes (default: the
    machine's cores) started here and closed on leaving, its scratch folder removed. Connecting, starting,
    and finding at least one worker take at most ``start_timeout`` seconds, or DistributedError says so.
    ``dashboard``: an address ("127.0.0.1:8787") for the LocalCluster's dashboard; None: none."""
    if client is not None:
        yield client
        return
    distributed = _import_distributed()
    if scheduler:
        try:
            connected = distributed.Client(scheduler, timeout=start_timeout, set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise DistributedError("scheduler %s: no connection within %g s (%s)" % (
                scheduler, start_timeout, error)) from None
        try:
            _wait_for_workers(connected, scheduler, start_timeout)
            yield connected
        finally:
            with contextlib.suppress(Exception):  # a lost scheduler is not waited for
                connected.close(timeout=2)
        return
    n_workers = n_workers or os.cpu_count() or 1
    if n_workers < 1:
        raise DistributedError("n_workers is %d, must be at least 1" % n_workers)
    _export_environment()
    with scratch_folder("jointcomp-dask-") as scratch:  # named for this process: a kill's is removed next time
        local = _start_local(distributed, n_workers, start_timeout, dashboard, scratch)
        try:
            with distributed.Client(local, set_as_default=False) as connected:
                yield connected
        finally:
            local.close()


# Dask's periodic housekeeping, slowed down for the LocalCluster started here (a cluster you give keeps its
# own settings). With the defaults an idle LocalCluster of 2 workers took 129 ms of CPU a second (55 in the
# client, which hosts the scheduler and the nannies; 74 in the workers), 1.3 ms a draw at 100 draws/s; with
# these, 14 (docs/performance.md). What they slow: the event loops' health check (every 20 ms: a blocked
# loop is still reported after 3 s), the workers' statistical profiler (a stack sample every 10 ms, for the
# dashboard), the system monitor (every 0.5 s, for the dashboard) and the workers' memory check (0.1 s;
# no result is kept on a worker here, a batch's memory is its own). The scheduler, in this process, logs
# each task's transitions (4) and events (1) for debugging, about 2 kB a task, up to 100,000 of each: 10,000
# are kept, so that what the client holds of them stops growing after 2,500 to 10,000 batches (a few MB).
LOCAL_CONFIG = {
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.transition-log-length": 10000,
    "distributed.scheduler.events-log-length": 10000,
}


def _start_local(distributed, n_workers, start_timeout, dashboard, scratch):
    # The scheduler's HTTP server starts whatever the dashboard setting: on loopback and a free port unless a
    # dashboard address is asked for (dashboard_address=None alone still bound 0.0.0.0:8787).
    scheduler_kwargs = {"dashboard": dashboard is not None, "dashboard_address": dashboard or "127.0.0.1:0"}
    # The workers start with Ctrl-C ignored (a signal ignored stays so in a new process): it reaches the whole
    # process group, and this process, not each worker with its own traceback, stops the run and the cluster.
    main_thread = threading.current_thread() is threading.main_thread()
    interrupt = signal.signal(signal.SIGINT, signal.SIG_IGN) if main_thread else None
    import dask
    try:
        with dask.config.set(LOCAL_CONFIG):  # read by the scheduler and the nannies, handed to the workers
            return distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                            host="127.0.0.1", dashboard_address=None,
                                            scheduler_kwargs=scheduler_kwargs, local_directory=scratch,
                                            silence_logs=40, timeout=start_timeout)
    except (TimeoutError, OSError, RuntimeError) as error:
        raise DistributedError("the local cluster of %d workers did not start within %g s (%s)" % (
            n_workers, start_timeout, error)) from None
    finally:
        if main_thread:
            signal.signal(signal.SIGINT, interrupt)


WORKER_WAIT = 10.0  # s: the longest a scheduler without workers is waited for


def _wait_for_workers(client, scheduler, start_timeout):
    wait = min(start_timeout, WORKER_WAIT)
    try:
        client.wait_for_workers(1, timeout=wait)
    except (TimeoutError, OSError) as error:
        raise DistributedError("scheduler %s has no worker (none joined within %g s): start workers with "
                               "`dask worker %s` (%s)" % (scheduler, wait, scheduler,
                                                          type(error).__name__)) from None


def _export_environment():
    """Local workers are new processes: they find this package and the library this process loaded."""
    import jointcomp
    package_root = str(pathlib.Path(jointcomp.__file__).resolve().parent.parent)
    paths = os.environ.get("PYTHONPATH", "").split(os.pathsep)
    if package_root not in paths:
        os.environ["PYTHONPATH"] = os.pathsep.join([package_root] + [p for p in paths if p])
    os.environ.setdefault("JOINTCOMP_LIBRARY", str(jointcomp.library_path))


def stream(client, function, job, items, merge, *, in_flight, timeout, retries, describe, scheduler=None):
    """``function(job, item)`` for every item, merged IN ITEM ORDER by ``merge(item, result)``, with at most
    ``in_flight`` tasks submitted and not yet merged (client memory bounded whatever the number of items).
    ``client`` None runs here. A task raising WorkerWithoutLibrary excludes its worker and runs again on
    the others. ``timeout``: seconds for all items. Raises DistributedError on a timeout, a lost scheduler,
    or no usable worker; on any exception (Ctrl-C too) the tasks in flight are cancelled first."""
    deadline = time.monotonic() + timeout
    if client is None:
        for item in items:
            merge(item, function(job, item))
            if time.monotonic() > deadline:
                raise DistributedError("%s: not done within %g s" % (describe, timeout))
        return
    items = enumerate(items)  # (sequence number, item): merged in that order
    pending, done, excluded = [], {}, set()
    in_progress = {}  # future key -> (future, numbered): what is submitted and not yet taken back
    # Finished futures arrive through their callbacks: the loop sleeps until one does (polling every 20 ms
    # cost the client 0.2 ms of CPU a draw), waking every WAKE s to check the deadline and the connection.
    finished = queue.Queue()
    where = scheduler or "the scheduler"
    _probe(client, excluded, describe)

    def submit(numbered, again=False):
        workers = _usable_workers(client, excluded, describe)
        future = client.submit(function, job, numbered[1], retries=retries, pure=False, workers=workers,
                               allow_other_workers=False)
        in_progress[future.key] = (future, numbered)
        future.add_done_callback(finished.put)
        if not again:
            pending.append(numbered[0])

    try:
        for numbered in items:
            submit(numbered)
            if len(pending) >= in_flight:
                break
        while pending:
            future, numbered = _next_done(finished, in_progress, client, deadline, describe, where, timeout)
            result = _result(future, numbered[1], client, excluded, describe, where)
            future.release()  # the scheduler forgets the result now, not when the future is collected
            if result is _AGAIN:
                submit(numbered, again=True)
                continue
            done[numbered[0]] = (numbered[1], result)
            while pending and pending[0] in done:
                merge(*done.pop(pending.pop(0)))
                following = next(items, None)
                if following is not None:
                    submit(following)
    except BaseException:
        if client.status == "running":  # a client that lost its scheduler would wait for it to cancel
            with contextlib.suppress(Exception):
                client.cancel([future for future, _ in in_progress.values()])
        raise


_AGAIN = object()


WAKE = 0.25  # s: how often a run waiting for its tasks checks its deadline and its scheduler


def _next_done(finished, in_progress, client, deadline, describe, where, timeout):
    """(future, numbered) of the next finished task; DistributedError past the deadline or once the
    scheduler is lost."""
    lost_since = None
    while True:
        if not in_progress:
            raise DistributedError("%s: no task left in flight (lost %s?)" % (describe, where))
        try:
            future = finished.get(timeout=WAKE)
        except queue.Empty:
            future = None
        if future is not None and future.key in in_progress:
            return in_progress.pop(future.key)
        now = time.monotonic()
        if now > deadline:
            raise DistributedError("%s: not done within %g s" % (describe, timeout))
        if client.status != "running":
            lost_since = lost_since or now
            if now - lost_since > LOST_AFTER:
                raise DistributedError("%s: lost %s (no connection for %g s)" % (describe, where, LOST_AFTER))
        else:
            lost_since = None


def _usable_workers(client, excluded, describe):
    """The workers not excluded, or None (any) when none is; DistributedError when every one is."""
    if not excluded:
        return None
    workers = [w for w in client.scheduler_info().get("workers", {}) if w not in excluded]
    if not workers:
        raise DistributedError("%s: no worker can load jointcomp (%d left out)" % (describe, len(excluded)))
    return workers


def can_load():
    """True on a worker that can import jointcomp and load its library (else unpickling this fails)."""
    return load_jointcomp() is not None


def _probe(client, excluded, describe):
    """Adds the workers that cannot load jointcomp to ``excluded``, saying so; True when one was added."""
    answers = client.run(can_load, on_error="return")
    added = False
    for worker, answer in sorted(answers.items()):
        if answer is not True and worker not in excluded:
            excluded.add(worker)
            added = True
            why = answer.args[1] if isinstance(answer, WorkerWithoutLibrary) else "%s: %s" % (
                type(answer).__name__, answer)
            print("jointcomp: worker %s left out: it cannot load jointcomp (%.300s)" % (worker, why), flush=True)
    if answers and len(excluded) >= len(answers):
        raise DistributedError("%s: no worker can load jointcomp (%d left out)" % (describe, len(excluded)))
    return added


def _result(future, item, client, excluded, describe, where):
    """The future's result; _AGAIN when its worker turned out to lack the library (it is then excluded)."""
    if future.status == "cancelled":  # the client cancels every future when it loses the scheduler
        raise DistributedError("%s: lost %s (its tasks were cancelled)" % (describe, where))
    try:
        return future.result()
    except (WorkerWithoutLibrary, ImportError) as error:
        if _probe(client, excluded, describe):
            return _AGAIN
        raise DistributedError("%s: a worker cannot load jointcomp: %.300s" % (describe, error)) from None
    except Exception as error:
        name = type(error).__name__
        if name in ("CancelledError", "FutureCancelledError", "CommClosedError") or isinstance(error, OSError):
            raise DistributedError("%s: lost %s (%s)" % (describe, where, name)) from None
        if name == "KilledWorker":
            raise DistributedError("%s: task %.100r killed its workers again and again (%.200s)" % (
                describe, item, error)) from None
        raise DistributedError("%s: task %.100r failed: %s: %.500s" % (describe, item, name, error)) from None
