"""What a Monte Carlo found, read from its merged summary: percentiles with their confidence intervals, the
band along the path, the text summary, montecarlo.json and the band's plot. Units: mm in every output."""

import json

import numpy as np

from .._paths import write_atomically
from .summary import CONFIDENCE, METRIC_NAMES, PERCENTILES, RUN_KEYS, smallest_sample

_FORMAT = "jointcomp-montecarlo/2"


class MonteCarloResult:
    """``merged`` (the merged Summary), ``samples``, ``seed``, ``use_plant``, ``distribution``,
    ``not_propagated``, ``failed`` ({draw: message}), ``band_z`` and ``band_norm`` (3 runs x 3 percentiles x
    band points, m) at ``time`` (s), and :meth:`statistics`, :meth:`summary`, :meth:`to_json`,
    :meth:`plot`, :meth:`write`."""

    def __init__(self, summary, job, samples, not_propagated, time):
        self.merged = summary
        self.samples = samples
        self.seed = job["seed"]
        self.use_plant = job["use_plant"]
        self.distribution = job["distribution"]
        self.not_propagated = list(not_propagated)
        self.failed = dict(sorted(summary.failed.items()))
        self.time = np.asarray(time)
        if summary.succeeded == 0:
            first = next(iter(self.failed.values()), "no draw ran")
            raise _error("monte carlo: every one of the %d draws failed; the first: %s" % (samples, first))
        self.band_z, self.band_norm = summary.band()

    def statistics(self):
        """Per run and metric, each percentile in mm with its distribution-free confidence interval
        ({"mm": x, "ci_mm": [low, high]}, a side None when the draws are too few), and the max error's 95 %
        bound ("max_within_mm_95")."""
        runs = {}
        for r, key in enumerate(RUN_KEYS):
            runs[key] = {}
            for m, name in enumerate(METRIC_NAMES):
                cells = {}
                for p in PERCENTILES:
                    value, low, high = self.merged.percentile(r, m, p)
                    cells["p%d" % p] = {"mm": value * 1e3, "ci_mm": [None if low is None else low * 1e3,
                                                                    None if high is None else high * 1e3]}
                runs[key][name] = cells
            runs[key]["max_within_mm_95"] = runs[key]["max"]["p95"]["mm"]
        return runs

    def warnings(self):
        """What the number of draws cannot support."""
        needed = smallest_sample(max(PERCENTILES) / 100.0)
        if self.merged.succeeded >= needed:
            return []
        return ["%d draws are too few for a %g %% confidence interval on the %d th percentile (both sides need at "
                "least %d): the reported percentile is a rough estimate" % (
                    self.merged.succeeded, 100 * CONFIDENCE, max(PERCENTILES), needed)]

    def to_json(self):
        """Everything as a JSON-ready dict (montecarlo.json); every length in mm."""
        return {
            "format": _FORMAT, "units": "mm",
            "samples": self.samples, "succeeded": self.merged.succeeded, "seed": self.seed,
            "seed_scheme": "draw k: numpy Generator(PCG64(SeedSequence([seed, k]))): one draw per entry, in order, "
                           "then the tracker's noise seed integers(0, 2**62)",
            "simulated_robot": "flexible-joint plant" if self.use_plant else "quasi-static",
            "percentiles": list(PERCENTILES), "confidence": CONFIDENCE,
            "percentile_definition": "nearest rank, read from logarithmic bins 0.1 % wide; intervals from order "
                                     "statistics (distribution-free)",
            "runs": self.statistics(),
            "warnings": self.warnings(),
            "failed": {str(k): v for k, v in self.failed.items()},
            "stiffness_draws_clamped": self.merged.clamped,
            "distribution": [_plain(e) for e in self.distribution],
            "not_propagated": self.not_propagated,
            "band": {"time_s": self.time.tolist(), "percentiles": list(PERCENTILES),
                     "z_mm": (self.band_z * 1e3).tolist(), "norm_mm": (self.band_norm * 1e3).tolist()},
        }

    def summary(self):
        """The percentile table, the 95 % bounds with their intervals, and the warnings, as text."""
        stats = self.statistics()
        lines = ["Monte Carlo: %d draws (seed %d, %s robot), %d failed; percentiles 5 / 50 / 95 over the draws, mm"
                 % (self.samples, self.seed, "flexible-joint plant" if self.use_plant else "quasi-static",
                    len(self.failed)),
                 "%-14s %-26s %-26s %-26s %-26s" % ("run", "Ra", "Rz", "RMS 3-D", "max 3-D")]
        for key in RUN_KEYS:
            cells = ["%.4f / %.4f / %.4f" % tuple(stats[key][m]["p%d" % p]["mm"] for p in PERCENTILES)
                     for m in METRIC_NAMES]
            lines.append("%-14s %-26s %-26s %-26s %-26s" % (key, *cells))
        for key, what in (("compensated", "compensated"), ("uncompensated", "uncompensated")):
            p95 = stats[key]["max"]["p95"]
            lines.append("In 95 %% of the draws the %s path stays within %.4f mm (max 3-D error); %g %% confidence "
                         "interval of that percentile: %s." % (what, p95["mm"], 100 * CONFIDENCE,
                                                                _interval(p95["ci_mm"])))
        lines += ["Warning: " + w for w in self.warnings()]
        if self.not_propagated:
            lines.append("Not propagated: " + "; ".join(self.not_propagated))
        if self.merged.clamped:
            lines.append("%d stiffness draws fell at or below zero and were held at 1 %% of the value"
                         % self.merged.clamped)
        shown = list(self.failed.items())[:20]
        lines += ["draw %d failed: %s" % (k, message) for k, message in shown]
        if len(self.failed) > len(shown):
            lines.append("... and %d more failed draws (montecarlo.csv, montecarlo.json)" % (len(self.failed) - 20))
        return "\n".join(lines)

    def plot(self, path):
        """The band (5 to 95 %) and the median of the error along the path, uncompensated and compensated:
        Z deviation above, 3-D error norm below."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        figure, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
        for r, colour in ((0, "tab:red"), (2, "tab:blue")):
            label = "without correction" if r == 0 else "stiffness and kinematic correction"
            for axis, band in ((axes[0], self.band_z), (axes[1], self.band_norm)):
                axis.fill_between(self.time, band[r, 0] * 1e3, band[r, 2] * 1e3, color=colour, alpha=0.25,
                                  linewidth=0, label=label + ": 5-95 %")
                axis.plot(self.time, band[r, 1] * 1e3, color=colour, linewidth=0.8, label=label + ": median")
        axes[0].set_ylabel("Z deviation [mm]")
        axes[1].set_ylabel("3-D error [mm]")
        axes[1].set_xlabel("time along the spiral [s]")
        axes[0].set_title("Spiral error under parameter uncertainty: %d draws, seed %d" % (self.samples, self.seed))
        axes[1].legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2, fontsize=8)
        figure.tight_layout()
        save_figure(figure, path)
        plt.close(figure)

    def write(self, folder):
        """montecarlo.json and montecarlo_band.png into ``folder`` (montecarlo.csv is streamed by the run)."""
        import pathlib
        folder = pathlib.Path(folder)
        write_text(folder / "montecarlo.json", json.dumps(self.to_json(), indent=2) + "\n")
        self.plot(folder / "montecarlo_band.png")


def _interval(ci):
    low, high = ci
    return "[%s, %s] mm" % ("below the smallest draw" if low is None else "%.4f" % low,
                            "above the largest draw" if high is None else "%.4f" % high)


def _plain(entry):
    """A distribution entry without the correlation's computed factor."""
    if "correlation" in entry:
        return {"correlation": {k: v for k, v in entry["correlation"].items() if k != "factor"}}
    return entry


def _error(message):
    from .laws import DistributedError
    return DistributedError(message)


def write_text(path, text):
    """Whole or not at all, and no temporary left by a kill (jointcomp._paths.write_atomically)."""
    write_atomically(path, lambda stream: stream.write(text.encode("utf-8")))


def save_figure(figure, path):
    """Writes a matplotlib figure to ``path`` as PNG, whole or not at all."""
    # No date or version in the PNG: a resumed run's plot has the same bytes.
    write_atomically(path, lambda stream: figure.savefig(stream, dpi=110, format="png", metadata={"Software": None}))
