#!/usr/bin/env python3
"""The main job's spiral under parameter uncertainty, on a local Dask cluster: how far the compensated and
the uncompensated paths stay from the plan in 95 % of the robots the nominal RX170 parameters may stand for.

usage: /usr/bin/python3 examples/python/montecarlo.py [--samples N] [--workers N] [--quasi-static] [--out DIR]
       [--report REPORT.json --urdf URDF --params PARAMS.json]

No identification report of the RX170 ships in the repository (its parameters are the paper's and
jointcomp's estimates: model/params/rx170.json), so the law is the main job's perturbation of the truth
(README, "The main job"): every stiffness x (1 + U(-5 %, 5 %)), every harmonic amplitude x (1 + U(-10 %,
10 %)), every phase + U(-0.1, 0.1) rad, the spring balancer's other values x (1 + U(-2 %, 2 %)), drawn
independently for each of N simulated robots, each simulated as the flexible-joint plant. Give --report (with the identified robot's --urdf and
--params) to use the standard errors an identification, calibration or discovery report states instead.
Writes DIR/montecarlo.json, montecarlo.csv and montecarlo_band.png (the 5-95 % band along the path).
"""

import argparse
import pathlib
import sys

checkout = pathlib.Path(__file__).resolve().parents[2]
try:
    import jointcomp
except ImportError:
    sys.path.insert(0, str(checkout / "capi" / "python"))
    import jointcomp
from jointcomp import distributed  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=40)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2019)
    parser.add_argument("--quasi-static", action="store_true",
                        help="simulate the quasi-static robot (default: the flexible-joint plant, as the main job)")
    parser.add_argument("--urdf", default=str(checkout / "model" / "robots" / "rx170.urdf"))
    parser.add_argument("--params", default=str(checkout / "model" / "params" / "rx170.json"))
    parser.add_argument("--report", help="report.json of the identified robot (--urdf, --params)")
    parser.add_argument("--out", default="out/montecarlo_example")
    arguments = parser.parse_args()
    result = distributed.monte_carlo(arguments.urdf, arguments.params, samples=arguments.samples,
                                     seed=arguments.seed, report=arguments.report, use_plant=not arguments.quasi_static,
                                     n_workers=arguments.workers, timeout=600, out=arguments.out,
                                     progress=distributed.console_progress())
    print(result.summary())
    print("wrote %s/montecarlo_band.png" % arguments.out)


if __name__ == "__main__":
    main()
