"""Mergeable summaries of Monte Carlo draws: what a worker reduces a batch to, and the client adds up.

Everything is a count in fixed bins, so that merging is exact integer addition: the merged summary does not
depend on how the draws were batched, on the order the batches came back, or on a resumed run.
* The metrics (3 runs x Ra, Rz, RMS, max, in m): a histogram each over logarithmic bins of relative width
  METRIC_STEP (0.1 %) from METRIC_LOW to METRIC_HIGH, with an underflow and an overflow bin, and the exact
  smallest and largest value. A percentile is read as its bin's geometric centre (within 0.05 %).
* The band along the path (Z deviation and 3-D error norm at `band points`, per run): histograms over
  coarser bins (BAND_STEP, 5 %; the Z deviation with a bin per sign) from which the 5 / 50 / 95 % band is
  read at each point.
"""

import math

import numpy as np

PERCENTILES = (5, 50, 95)
RUN_KEYS = ("uncompensated", "stiffness", "compensated")  # the spiral's three runs (jointcomp.RUN_NAMES)
METRIC_NAMES = ("ra", "rz", "rms", "max")  # of the five metrics of a run, the ones reported
METRIC_LOW, METRIC_HIGH, METRIC_STEP = 1e-9, 1.0, 1e-3
BAND_LOW, BAND_HIGH, BAND_STEP = 1e-7, 0.1, 0.05
CONFIDENCE = 0.95


def _bin_count(low, high, step):
    return int(math.ceil(math.log(high / low) / math.log1p(step)))


METRIC_BINS = _bin_count(METRIC_LOW, METRIC_HIGH, METRIC_STEP) + 2  # 0: below LOW (or 0), last: above HIGH
BAND_MAGNITUDE_BINS = _bin_count(BAND_LOW, BAND_HIGH, BAND_STEP) + 2
BAND_Z_BINS = 2 * BAND_MAGNITUDE_BINS - 1  # negative magnitudes mirrored, the "below LOW" bin shared


def _log_bins(values, low, high, step, bins):
    """Bin index of each value >= 0: 0 below ``low``, bins - 1 above ``high``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        index = np.floor(np.log(np.maximum(values, low) / low) / math.log1p(step)).astype(np.int64) + 1
    index[values < low] = 0
    return np.minimum(index, bins - 1)


def _centres(low, step, bins):
    """The value each bin stands for: its geometric centre (0 for the underflow bin)."""
    k = np.arange(bins, dtype=np.float64)
    centres = low * np.power(1.0 + step, k - 0.5)
    centres[0] = 0.0
    return centres


class Summary:
    """The merged counts of a set of draws. ``metrics`` (3, 4, METRIC_BINS), ``band_norm`` (3, P,
    BAND_MAGNITUDE_BINS) and ``band_z`` (3, P, BAND_Z_BINS) are counts; ``low`` and ``high`` (3, 4) the exact
    extremes; ``draws`` the draws seen, ``failed`` {index: message} of those that failed, ``clamped`` the
    stiffness draws held at 1 %."""

    def __init__(self, band_points):
        self.band_points = band_points
        self.draws = 0
        self.clamped = 0
        self.failed = {}
        self.metrics = np.zeros((3, 4, METRIC_BINS), dtype=np.int64)
        self.low = np.full((3, 4), np.inf)
        self.high = np.full((3, 4), -np.inf)
        self.band_norm = np.zeros((3, band_points, BAND_MAGNITUDE_BINS), dtype=np.int64)
        self.band_z = np.zeros((3, band_points, BAND_Z_BINS), dtype=np.int64)

    @property
    def succeeded(self):
        """The draws that gave metrics (all draws less the failed ones)."""
        return self.draws - len(self.failed)

    def add_draw(self, metrics, z, norm):
        """One successful draw: ``metrics`` (3, 5) in m, ``z`` and ``norm`` (3, P) along the band's points."""
        values = metrics[:, :4]
        # One bin per (run, metric) and per (run, point): flat indices, all distinct, so one += adds them.
        metric_bins = _log_bins(values, METRIC_LOW, METRIC_HIGH, METRIC_STEP, METRIC_BINS)
        self.metrics.reshape(-1)[np.arange(12) * METRIC_BINS + metric_bins.ravel()] += 1
        np.minimum(self.low, values, out=self.low)
        np.maximum(self.high, values, out=self.high)
        magnitude, norm_bins = _log_bins(np.stack([np.abs(z), norm]), BAND_LOW, BAND_HIGH, BAND_STEP,
                                         BAND_MAGNITUDE_BINS)
        centre = BAND_MAGNITUDE_BINS - 1
        signed = np.where(z < 0.0, centre - magnitude, centre + magnitude)
        rows = np.arange(3 * self.band_points)
        self.band_z.reshape(-1)[rows * BAND_Z_BINS + signed.ravel()] += 1
        self.band_norm.reshape(-1)[rows * BAND_MAGNITUDE_BINS + norm_bins.ravel()] += 1
        self.draws += 1

    def add_failure(self, index, message):
        """One failed draw: its index and the library's message."""
        self.failed[int(index)] = message
        self.draws += 1

    def merge(self, other):
        """Adds ``other`` (of other draws) into this summary."""
        self.draws += other.draws
        self.clamped += other.clamped
        self.failed.update(other.failed)
        np.minimum(self.low, other.low, out=self.low)
        np.maximum(self.high, other.high, out=self.high)
        for key in self._COUNTS:
            where, counts = other._nonzero(key)
            getattr(self, key).reshape(-1)[where] += counts  # distinct indices: one += adds them

    # ---- reading it ----

    def percentile(self, run, metric, p):
        """(value, low, high) in m: percentile ``p`` of a metric (nearest rank: the smallest draw with at
        least p % of the draws at or below it) and its distribution-free confidence interval (order
        statistics, CONFIDENCE); low / high are None where the draws are too few to bound that side."""
        counts = self.metrics[run, metric]
        n = int(counts.sum())
        cumulative = np.cumsum(counts)
        centres = _centres(METRIC_LOW, METRIC_STEP, METRIC_BINS)
        extremes = (self.low[run, metric], self.high[run, metric])

        def order_statistic(rank):  # the rank-th smallest draw (1-based), as its bin reads it
            if rank == 1:
                return float(extremes[0])
            if rank == n:
                return float(extremes[1])
            b = int(np.searchsorted(cumulative, rank))
            return float(centres[b]) if 0 < b < METRIC_BINS - 1 else float(extremes[0] if b == 0 else extremes[1])

        rank = max(1, int(math.ceil(p / 100.0 * n)))
        lower, upper = confidence_ranks(n, p / 100.0, CONFIDENCE)
        return (order_statistic(rank), None if lower is None else order_statistic(lower),
                None if upper is None else order_statistic(upper))

    def band(self):
        """(band_z, band_norm), each (3 runs, 3 percentiles, P points) in m: the 5 / 50 / 95 % of the draws
        at each point of the band, as the bins read them."""
        magnitudes = _centres(BAND_LOW, BAND_STEP, BAND_MAGNITUDE_BINS)
        z_values = np.concatenate([-magnitudes[:0:-1], magnitudes])
        return (self._band_percentiles(self.band_z, z_values), self._band_percentiles(self.band_norm, magnitudes))

    @staticmethod
    def _band_percentiles(counts, values):
        cumulative = np.cumsum(counts, axis=2)
        total = cumulative[:, :, -1:]
        out = np.empty((counts.shape[0], len(PERCENTILES), counts.shape[1]))
        for i, p in enumerate(PERCENTILES):
            rank = np.maximum(1, np.ceil(p / 100.0 * total))
            index = (cumulative < rank).sum(axis=2)
            out[:, i, :] = values[np.minimum(index, len(values) - 1)]
        return out

    # ---- on the wire: a batch's counts are mostly zeros, so they travel as (shape, where, count) ----
    # and stay so on arrival (``_packed``) until read: merging them adds the non-zero counts alone, where
    # making them dense first (8 MB a batch) cost the client 10 ms a batch of CPU.

    _COUNTS = ("metrics", "band_norm", "band_z")

    def _nonzero(self, key):
        """(flat indices, counts) of the non-zero counts of ``key``."""
        return self._sparse(key)[1:]

    def _sparse(self, key):
        """(shape, flat indices, counts) of the non-zero counts of ``key``, unpacking nothing."""
        packed = self.__dict__.get("_packed")
        if packed is not None and key in packed:
            return packed[key]
        dense = getattr(self, key)
        where = np.flatnonzero(dense)
        return dense.shape, where, dense.reshape(-1)[where]

    def __getstate__(self):
        state = {k: v for k, v in self.__dict__.items() if k not in self._COUNTS and k != "_packed"}
        state["_packed"] = {key: self._sparse(key) for key in self._COUNTS}
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)

    def __getattr__(self, name):
        # Called only for a missing attribute: the counts of a summary that travelled, made dense when read.
        packed = self.__dict__.get("_packed")
        if packed is None or name not in packed:
            raise AttributeError(name)
        shape, where, counts = packed.pop(name)
        dense = np.zeros(shape, dtype=np.int64)
        np.put(dense, where, counts)
        self.__dict__[name] = dense
        return dense

    # ---- the checkpoint's form ----

    def arrays(self):
        """The summary as named arrays (numpy .npz), the counts sparse ("<name>_shape", "<name>_where",
        "<name>_counts": a dense checkpoint was 8 MB written every 2 s); failures go separately."""
        arrays = {"draws": np.int64(self.draws), "clamped": np.int64(self.clamped), "low": self.low,
                  "high": self.high}
        for key in self._COUNTS:
            shape, where, counts = self._sparse(key)
            arrays.update({key + "_shape": np.array(shape, dtype=np.int64), key + "_where": where,
                           key + "_counts": counts})
        return arrays

    @classmethod
    def from_arrays(cls, arrays, failed):
        """The summary of ``arrays`` (as arrays() gives them) and ``failed`` ((index, message) pairs)."""
        summary = cls(int(arrays["band_norm_shape"][1]))
        summary.draws, summary.clamped = int(arrays["draws"]), int(arrays["clamped"])
        summary.low, summary.high = np.array(arrays["low"]), np.array(arrays["high"])
        for key in cls._COUNTS:
            dense = getattr(summary, key)
            if dense.shape != tuple(arrays[key + "_shape"]):
                raise ValueError("%s has shape %s, expected %s" % (key, tuple(arrays[key + "_shape"]), dense.shape))
            dense.reshape(-1)[arrays[key + "_where"]] = arrays[key + "_counts"]
        summary.failed = {int(k): v for k, v in failed}
        return summary


def confidence_ranks(n, q, confidence=CONFIDENCE):
    """Ranks (l, u), 1-based, of the order statistics X_(l) <= x_q <= X_(u) with probability at least
    ``confidence`` for any continuous distribution (binomial(n, q) tails of (1 - confidence) / 2 each);
    None for a side the n draws cannot bound. Exact binomial sums in logarithms."""
    if n <= 0:
        return None, None
    k = np.arange(n + 1, dtype=np.float64)
    steps = np.log(n - k[:-1]) - np.log(k[:-1] + 1.0) + math.log(q) - math.log1p(-q)
    log_pmf = np.concatenate([[n * math.log1p(-q)], n * math.log1p(-q) + np.cumsum(steps)])
    cdf = np.cumsum(np.exp(log_pmf - log_pmf.max())) * math.exp(log_pmf.max())
    alpha = (1.0 - confidence) / 2.0
    # P(X_(l) <= x_q) = P(Binomial(n, q) >= l) = 1 - cdf[l - 1] >= 1 - alpha: the largest such l.
    lows = np.nonzero(cdf[:n] <= alpha)[0]
    lower = int(lows[-1]) + 1 if lows.size else None
    # P(X_(u) >= x_q) = P(Binomial(n, q) <= u - 1) = cdf[u - 1] >= 1 - alpha: the smallest such u.
    highs = np.nonzero(cdf[:n] >= 1.0 - alpha)[0]
    upper = int(highs[0]) + 1 if highs.size else None
    return lower, upper


def smallest_sample(q, confidence=CONFIDENCE):
    """The fewest draws for which percentile q (0 to 1) gets a two-sided interval at ``confidence``."""
    alpha = (1.0 - confidence) / 2.0
    return int(math.ceil(math.log(alpha) / math.log(max(q, 1.0 - q))))
