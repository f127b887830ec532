"""Past one machine: Monte Carlo accuracy with confidence intervals, and fleet calibration, on Dask.

Two jobs, each spread over a Dask cluster (a ``client=`` you give, a scheduler address, or a LocalCluster
of worker processes started here):

* :func:`monte_carlo` draws N parameter sets from a distribution (the uncertainty an identification,
  calibration or discovery report states, the main job's perturbation as the library states it, or your
  own: laws.py), and for each runs the paper's spiral compensated with the NOMINAL parameters on a simulated
  robot whose truth is the DRAWN set. Draws travel in batches, each reduced on its worker to a mergeable
  summary (summary.py), so the client's memory does not depend on N; a checkpoint lets a stopped run resume
  to the same bytes (montecarlo.py). It reports percentiles of Ra, Rz, RMS and max error with
  distribution-free confidence intervals, and the error band along the path (results.py).
* :func:`fleet` calibrates (or runs discovery on) many campaign files, one robot each: a report folder per
  robot and a fleet summary with outliers flagged (fleet.py).

Only inputs (file contents, JSON text, seeds) and results (numbers, arrays, summaries) travel between the
client and the workers: every worker loads its own library, no ctypes handle is ever shipped, no shared file
system is needed. Draw k of seed s comes from its own generator, ``numpy.random.Generator(PCG64(
SeedSequence([s, k])))`` (laws.py states the scheme), so the results do not depend on the number of workers,
the batch size, or the order the tasks run.

Command line: ``/usr/bin/python3 -m jointcomp.distributed montecarlo|fleet ...`` (what ``jointcomp
montecarlo`` and ``jointcomp fleet`` run); ``--help`` lists the options.
"""

from .streaming import cluster
from .fleet import OUTLIER_RULE, FleetResult, fleet
from .laws import (DistributedError, check_distribution, load_distribution, main_job_distribution,
                   report_distribution, sample_generator)
from .montecarlo import DEFAULT_SEED, MAX_SAMPLES, Interrupted, console_progress, monte_carlo
from .results import MonteCarloResult
from .summary import PERCENTILES, RUN_KEYS, METRIC_NAMES, Summary, confidence_ranks

__all__ = ["DEFAULT_SEED", "DistributedError", "FleetResult", "Interrupted", "MAX_SAMPLES", "METRIC_NAMES",
           "MonteCarloResult", "OUTLIER_RULE", "PERCENTILES", "RUN_KEYS", "Summary", "check_distribution", "cluster",
           "confidence_ranks", "console_progress", "fleet", "load_distribution", "main_job_distribution",
           "monte_carlo", "report_distribution", "sample_generator"]
