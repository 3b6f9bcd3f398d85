"""The statistics of the results tables, in one place: the summary of an evaluation table
(:func:`summarize`), the standard deviations, the efficiency gains and their intervals.

Two conventions are in use, each because numbers published under ``docs/results`` were computed
with it and must re-derive unchanged from their stored rows:

* :func:`sample_std` (divisor n - 1): the evaluation tables. :func:`summarize`
  (``summary.json``, ``vgs evaluate``), the report's tables and ``results.csv``, and the spread
  of the gain between training seeds (``vgs seeds``).
* :func:`population_std` (divisor n): the grasp-position sweep. ``sweep.summarize``
  (``summary.json``, the table ``vgs sweep`` prints) and the error bars of ``sweep.png``.

With 20 trials per offset the two differ by a factor sqrt(20 / 19), about 2.6 %.

The efficiency gain of VGS over the baseline (:func:`efficiency_gain`, the report and ``vgs
seeds``): ``100 (T_base - T_vgs) / T_base`` on the mean successful assembly times, with a paired
bootstrap 95 % interval over the test episodes. The same on the *total* simulated time of all
test attempts (:func:`total_gain_pct`, ``vgs seeds``) is the paper's own measure; its tests all
assembled, so there the two coincide. The same total over the successes alone
(:func:`success_total_gain_pct`) leaves the failed attempts out, and the gain on the mean
alignment time of the successes (:data:`ALIGN_GAIN`) isolates the phase the paper studies. Each
is a :class:`Measure` (:data:`GAINS`) that knows its time column and how many successes its
interval needs.

Over few training seeds, the spread between runs is estimated from n values: besides the
crossed bootstrap of ``vgs seeds``, :func:`t_interval` gives Student's t interval of the mean.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd


def sample_std(values: Sequence[float] | np.ndarray) -> float:
    """Standard deviation with divisor n - 1; NaN for fewer than two values."""
    values = np.asarray(values, dtype=float)
    return float(np.std(values, ddof=1)) if values.size > 1 else math.nan


def population_std(values: Sequence[float] | np.ndarray) -> float:
    """Standard deviation with divisor n (NumPy's default); NaN for no values."""
    values = np.asarray(values, dtype=float)
    return float(np.std(values)) if values.size else math.nan


BOOTSTRAP_RESAMPLES = 2000


# Fewer successful assemblies than this per policy: times are not compared (no verdict, no CI).
MIN_SUCCESSES = 5


@dataclass(frozen=True)
class Gain:
    """Efficiency gain of VGS over the baseline [%] with its bootstrap 95 % interval."""

    value: float
    low: float
    high: float
    paired: bool
    n: int

    def text(self) -> str:
        if not math.isfinite(self.value):
            return "n/a"
        if not math.isfinite(self.low):
            return f"{self.value:+.2f} % [too few successes]"
        return f"{self.value:+.2f} % [{self.low:+.2f}, {self.high:+.2f}]"


def _mean_success(times: np.ndarray, ok: np.ndarray) -> float:
    return float(times[ok].mean()) if ok.any() else math.nan


def time_arrays(df: pd.DataFrame, column: str = "assembly_time_s"
                ) -> tuple[np.ndarray, np.ndarray]:
    """``(column, assembly_success)`` of an evaluation table, ordered by episode index; the
    time column is the whole assembly's by default (``time_align_s`` for the alignment)."""
    df = df.sort_values("index")
    return df[column].to_numpy(float), df["assembly_success"].to_numpy(bool)


def gain_pct(tb: np.ndarray, ob: np.ndarray, tv: np.ndarray, ov: np.ndarray) -> float:
    """``100 (T_base - T_vgs) / T_base`` on the mean times of the successes (NaN without any,
    or when the baseline's mean is zero: a phase its successes never entered)."""
    mb, mv = _mean_success(tb, ob), _mean_success(tv, ov)
    return (100.0 * (mb - mv) / mb if math.isfinite(mb) and math.isfinite(mv) and mb > 0
            else math.nan)


def total_gain_pct(tb: np.ndarray, ob: np.ndarray, tv: np.ndarray, ov: np.ndarray) -> float:
    """``100 (S_base - S_vgs) / S_base`` on the summed assembly times of *all* attempts.

    ``S = sum_i t_i`` over every test, a failed attempt with its time until it was given up and
    a missed grasp (time NaN) with none, as ``time_all_h`` of
    :func:`summarize`. A policy that fails often pays for each failure
    here, which the mean of the successes (:func:`gain_pct`) does not see. The success flags
    are not used; they keep the signature of :func:`gain_pct`.
    """
    del ob, ov
    sb, sv = float(np.nansum(tb)), float(np.nansum(tv))
    return 100.0 * (sb - sv) / sb if sb > 0 else math.nan


def success_total_gain_pct(tb: np.ndarray, ob: np.ndarray, tv: np.ndarray,
                           ov: np.ndarray) -> float:
    """``100 (S_base - S_vgs) / S_base`` on the summed assembly times of the *successes* only:
    the total time with every failed attempt left out (NaN without successes)."""
    sb, sv = float(tb[ob].sum()), float(tv[ov].sum())
    return 100.0 * (sb - sv) / sb if sb > 0 and ov.any() else math.nan


@dataclass(frozen=True)
class Measure:
    """A gain of VGS over the baseline on given tests, ``fn(tb, ob, tv, ov)`` [%], the time
    column it reads and the fewest successes per policy for which its interval is given."""

    name: str
    fn: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], float]
    min_successes: int
    column: str = "assembly_time_s"

    def __call__(self, tb: np.ndarray, ob: np.ndarray, tv: np.ndarray, ov: np.ndarray) -> float:
        return self.fn(tb, ob, tv, ov)


# The column prefixes of vgs.columns (``gain_pct``, ``total_gain_pct`` and their intervals).
MEAN_GAIN = Measure("gain", gain_pct, MIN_SUCCESSES)
TOTAL_GAIN = Measure("total_gain", total_gain_pct, 0)  # a total needs no successes
SUCCESS_TOTAL_GAIN = Measure("success_total_gain", success_total_gain_pct, MIN_SUCCESSES)
ALIGN_GAIN = Measure("align_gain", gain_pct, MIN_SUCCESSES, column="time_align_s")
GAINS = (TOTAL_GAIN, SUCCESS_TOTAL_GAIN, MEAN_GAIN, ALIGN_GAIN)

# Student's t quantile t_{0.975, df} for df = 1..30 (beyond, the normal 1.96 plus 2.4 / df
# is within 0.002 of the exact value).
_T975 = (12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179,
         2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
         2.060, 2.056, 2.052, 2.048, 2.045, 2.042)


def t_interval(values: Sequence[float] | np.ndarray) -> tuple[float, float]:
    """Student's t 95 % interval of the mean of n values (NaN for n < 2),

        mean +- t_{0.975, n-1} * s / sqrt(n),   s the sample standard deviation.

    It assumes the values are normal draws; over a handful of training seeds it is wide
    (t = 2.78 for five), which is honest: n runs say little about the spread between runs.
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return math.nan, math.nan
    df = x.size - 1
    t = _T975[df - 1] if df <= len(_T975) else 1.96 + 2.4 / df
    half = t * sample_std(x) / math.sqrt(x.size)
    return float(x.mean() - half), float(x.mean() + half)


def efficiency_gain(base: pd.DataFrame, vgs: pd.DataFrame, resamples: int = BOOTSTRAP_RESAMPLES,
                    seed: int = 0, measure: Measure = MEAN_GAIN) -> Gain:
    """``100 (T_base - T_vgs) / T_base`` on mean successful assembly times, bootstrap 95 % CI.

    The interval is NaN when either policy has fewer than ``measure.min_successes`` successful
    assemblies (:data:`MIN_SUCCESSES` for the mean: a mean of one or two times has no useful
    interval). Episodes are paired by
    ``index`` when both tables hold the same indices (the same scenes); otherwise each table is
    resampled on its own. ``measure``: :data:`MEAN_GAIN` (above) or :data:`TOTAL_GAIN`.
    """
    if measure.column not in base.columns or measure.column not in vgs.columns:
        return Gain(math.nan, math.nan, math.nan, False, len(base))  # a table without it
    base = base.sort_values("index")
    vgs = vgs.sort_values("index")
    tb, ob = time_arrays(base, measure.column)
    tv, ov = time_arrays(vgs, measure.column)
    value = measure(tb, ob, tv, ov)
    paired = list(base["index"]) == list(vgs["index"])
    if not math.isfinite(value) or min(ob.sum(), ov.sum()) < measure.min_successes:
        return Gain(value, math.nan, math.nan, paired, len(base))
    rng = np.random.default_rng(seed)
    gains = np.empty(resamples)
    for b in range(resamples):
        ib = rng.integers(len(tb), size=len(tb))
        iv = ib if paired else rng.integers(len(tv), size=len(tv))
        gains[b] = measure(tb[ib], ob[ib], tv[iv], ov[iv])
    gains = gains[np.isfinite(gains)]
    low, high = (np.percentile(gains, [2.5, 97.5]) if gains.size else (math.nan, math.nan))
    return Gain(value, float(low), float(high), paired, len(base))


def summarize(df: pd.DataFrame) -> dict[str, Any]:
    """Success rates and assembly-time statistics of one evaluation table.

    The ``time_*`` statistics are those of the successful assemblies (the paper's measure);
    ``time_all_h`` is the simulated assembly time of all episodes, failed attempts included
    (each until it was given up; a missed grasp costs none): the paper's measure, the total time
    of its tests, every one of which assembled. ``time_per_assembled_s`` is that time divided by
    the number of pegs assembled.
    """
    ok = df[df["assembly_success"].astype(bool)]
    times = ok["assembly_time_s"].to_numpy(float)
    attempts = float(np.nansum(df["assembly_time_s"].to_numpy(float)))

    def stat(fn: Callable[[np.ndarray], Any]) -> float | None:
        return float(fn(times)) if times.size else None

    return {
        "episodes": int(len(df)), "grasp_success_rate": float(df["grasp_success"].mean()),
        "success_rate": float(len(ok) / max(len(df), 1)), "successes": int(len(ok)),
        "time_total_h": float(times.sum() / 3600.0), "time_mean_s": stat(np.mean),
        "time_std_s": stat(lambda t: sample_std(t) if t.size > 1 else 0.0),
        "time_min_s": stat(np.min), "time_max_s": stat(np.max),
        "time_median_s": stat(np.median),
        # Throughput: every assembly attempt's simulated time (a failed one until it was given
        # up; a missed grasp costs none) over the pegs assembled.
        "time_all_h": attempts / 3600.0,
        "time_per_assembled_s": attempts / len(ok) if len(ok) else None,
        "abs_grasp_offset_mean_mm": float(np.nanmean(np.abs(df["grasp_offset_mm"])))
        if df["grasp_offset_mm"].notna().any() else None,
        "failure_reasons": {str(k): int(v) for k, v in
                            df.loc[~df["assembly_success"].astype(bool), "failure_reason"]
                            .value_counts().items()},
    }
