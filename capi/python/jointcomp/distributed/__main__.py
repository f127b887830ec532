"""The command line of jointcomp.distributed: what `jointcomp montecarlo` and `jointcomp fleet` run."""

import argparse
import logging
import math
import sys

from .._paths import prepare_output_folder
from ..errors import JointcompError
from .fleet import fleet
from .laws import DistributedError
from .montecarlo import DEFAULT_SEED, MAX_SAMPLES, Interrupted, console_progress, monte_carlo


def _parser():
    parser = argparse.ArgumentParser(prog="jointcomp", description="Monte Carlo accuracy and fleet calibration "
                                     "on a Dask cluster (jointcomp.distributed)")
    commands = parser.add_subparsers(dest="command", required=True)
    mc = commands.add_parser("montecarlo", help="the spiral's accuracy under parameter uncertainty")
    mc.add_argument("--urdf", required=True)
    mc.add_argument("--params", required=True, help="the nominal (identified) parameter file")
    law = mc.add_mutually_exclusive_group()
    law.add_argument("--report", help="report.json whose standard errors give the law")
    law.add_argument("--distribution", help="JSON file: a list of {parameter, law, scale, relative}")
    mc.add_argument("--samples", type=int, default=100, help="number of draws, 1 to %d" % MAX_SAMPLES)
    mc.add_argument("--seed", type=int, default=DEFAULT_SEED)
    mc.add_argument("--plant", action="store_true", help="simulate the flexible-joint plant (needs drives)")
    mc.add_argument("--resume", action="store_true", help="continue the stopped run whose checkpoint is in --out")
    mc.add_argument("--batch", type=int, default=None, help="draws per task (default: about 2 s of work)")
    mc.add_argument("--out", default="out/montecarlo")
    fl = commands.add_parser("fleet", help="calibrate or discover many robots, one campaign each")
    fl.add_argument("--urdf", required=True)
    fl.add_argument("--params", required=True)
    fl.add_argument("--campaign", action="append", required=True, help="a campaign file (repeat for more)")
    fl.add_argument("--method", choices=("calibrate", "discover"), default="calibrate")
    fl.add_argument("--out", default="out/fleet")
    fl.add_argument("--holdout", action="append", default=[],
                    help="CAMPAIGN=HELD_OUT.csv: a held-out campaign of that robot (repeat for more)")
    for sub in (mc, fl):
        sub.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
        sub.add_argument("--workers", type=int, default=None, help="local worker processes (default: cores)")
        sub.add_argument("--timeout", type=float, default=3600.0, help="seconds for all tasks")
        sub.add_argument("--dashboard", default=None, help="serve the local cluster's dashboard at this address")
    return parser


def _montecarlo(arguments):
    if arguments.batch is not None and arguments.batch < 1:
        raise DistributedError("--batch is %d, must be at least 1" % arguments.batch)
    result = monte_carlo(arguments.urdf, arguments.params, samples=arguments.samples, seed=arguments.seed,
                         report=arguments.report, distribution=arguments.distribution, use_plant=arguments.plant,
                         out=arguments.out, resume=arguments.resume, progress=console_progress(),
                         scheduler=arguments.scheduler, n_workers=arguments.workers, timeout=arguments.timeout,
                         batch_size=arguments.batch, dashboard=arguments.dashboard)
    print(result.summary())
    print("wrote %s/montecarlo.{json,csv} and montecarlo_band.png" % arguments.out)
    return 0


def _fleet(arguments):
    holdouts = {}
    for item in arguments.holdout:
        campaign, separator, held = item.partition("=")
        if not separator or not campaign or not held:
            raise DistributedError("--holdout %r: expected CAMPAIGN=HELD_OUT.csv" % item)
        holdouts.setdefault(campaign, []).append(held)
    result = fleet(arguments.urdf, arguments.params, arguments.campaign, arguments.out, method=arguments.method,
                   holdouts=holdouts, scheduler=arguments.scheduler, n_workers=arguments.workers,
                   timeout=arguments.timeout, dashboard=arguments.dashboard)
    print(result.summary())
    print("wrote %s/<robot>/ and %s/fleet_summary.{csv,json,txt}, fleet.png" % (arguments.out, arguments.out))
    return 1 if result.failed else 0


def main(argv=None):
    arguments = _parser().parse_args(argv)
    # Dask's and Tornado's own logs of a lost connection are tracebacks; what went wrong is said once, below.
    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    try:
        if arguments.workers is not None and arguments.workers < 1:
            raise DistributedError("--workers is %d, must be at least 1" % arguments.workers)
        if not (math.isfinite(arguments.timeout) and arguments.timeout > 0):  # nan ended in a traceback
            raise DistributedError("--timeout is %r, must be a positive number of seconds" % arguments.timeout)
        prepare_output_folder(arguments.out, DistributedError)
        return _montecarlo(arguments) if arguments.command == "montecarlo" else _fleet(arguments)
    except Interrupted as error:
        print("jointcomp %s: %s" % (arguments.command, error), file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("jointcomp %s: interrupted" % arguments.command, file=sys.stderr)
        return 130
    except (DistributedError, JointcompError, OSError) as error:
        print("jointcomp %s: %s" % (arguments.command, error), file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
