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

from vgs.errors import ConfigError


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


# -- what a gap is made of: phases, grasp sites, failed attempts ---------------------------------
#
# Every decomposition below is exact: its rows sum to the quantity they split (up to float).

PHASE_PREFIX, PHASE_SUFFIX = "time_", "_s"
# |grasp_offset_mm| sites along the axis and across_mm sites across it (issue 52).
ALONG_SITE_EDGES_MM = (26.0, 35.0)
ALONG_SITES = ("within +-26 mm", "26-35 mm", "beyond 35 mm")
ACROSS_SITE_MM = 5.0
ACROSS_SITES = ("within 5 mm of the axis", "5 mm or more beside it")
NO_GRASP = "no grasp"


def com_shifted(df: pd.DataFrame) -> bool:
    """Whether some of an evaluation table's pegs have their centre of mass off the middle
    (the `com` conditions), so that the grasp's distance from the centre of mass
    (``grasp_offset_com_mm``, ground truth) differs from that from the middle."""
    return "peg_com_shift_mm" in df and "grasp_offset_com_mm" in df \
        and bool((df["peg_com_shift_mm"].fillna(0.0) != 0.0).any())


def phase_columns(df: pd.DataFrame) -> list[str]:
    """The ``time_<phase>_s`` columns of a table, in the table's (the phases') order."""
    return [c for c in df.columns if c.startswith(PHASE_PREFIX) and c.endswith(PHASE_SUFFIX)
            and c != "assembly_time_s"]


def phase_gap(base: pd.DataFrame, vgs: pd.DataFrame) -> dict[str, float]:
    """The gap in the mean time of successes, ``M_b - M_v``, split by phase [s]:

        M_b - M_v = sum_p (mean_b(t_p) - mean_v(t_p)),

    each mean over the policy's own successes; exact because every success's assembly time is
    the sum of its phase times (a row ``other`` takes what the phases do not hold, zero in
    the tables written so far). Keys: the phase names, ``other`` and ``gap``.
    """
    ob = base["assembly_success"].to_numpy(bool)
    ov = vgs["assembly_success"].to_numpy(bool)
    if not ob.any() or not ov.any():
        return {}
    gap = float(base["assembly_time_s"].to_numpy(float)[ob].mean()
                - vgs["assembly_time_s"].to_numpy(float)[ov].mean())
    out: dict[str, float] = {}
    for col in phase_columns(base):
        if col in vgs.columns:
            out[col[len(PHASE_PREFIX):-len(PHASE_SUFFIX)]] = float(
                base[col].to_numpy(float)[ob].mean() - vgs[col].to_numpy(float)[ov].mean())
    out["other"] = gap - sum(out.values())
    out["gap"] = gap
    return out


def phase_variance_shares(df: pd.DataFrame) -> dict[str, float]:
    """Each phase's share of the variance of the successes' assembly time,

        cov(t_phase, T) / var(T),   T = sum_p t_p,

    over the successes; the shares sum to 1 (a phase that varies with the total carries its
    part). Empty for fewer than two successes or no variance."""
    ok = df["assembly_success"].to_numpy(bool)
    total = df["assembly_time_s"].to_numpy(float)[ok]
    if total.size < 2 or np.var(total) == 0:
        return {}
    centred = total - total.mean()
    return {c[len(PHASE_PREFIX):-len(PHASE_SUFFIX)]: float(
        np.mean((df[c].to_numpy(float)[ok] - df[c].to_numpy(float)[ok].mean()) * centred)
        / np.var(total)) for c in phase_columns(df)}


def along_sites(offset_mm: np.ndarray | pd.Series) -> np.ndarray:
    """Each grasp's site along the axis (:data:`ALONG_SITES` by ``|grasp_offset_mm|``, the
    edges belonging to the outer site; :data:`NO_GRASP` for NaN)."""
    a = np.abs(np.asarray(offset_mm, dtype=float))
    out = np.full(a.shape, NO_GRASP, dtype=object)
    lo, hi = ALONG_SITE_EDGES_MM
    out[a < lo] = ALONG_SITES[0]
    out[(a >= lo) & (a < hi)] = ALONG_SITES[1]
    out[a >= hi] = ALONG_SITES[2]
    return out


def across_sites(df: pd.DataFrame) -> np.ndarray | None:
    """Each grasp's site across the axis (:data:`ACROSS_SITES` by ``|across_mm|``; signed or
    not, its magnitude), or None when the table does not hold ``across_mm`` (tables written
    before it was recorded) or holds no value in it."""
    if "across_mm" not in df.columns or not df["across_mm"].notna().any():
        return None
    a = np.abs(df["across_mm"].to_numpy(float))
    out = np.full(a.shape, NO_GRASP, dtype=object)
    out[a < ACROSS_SITE_MM] = ACROSS_SITES[0]
    out[a >= ACROSS_SITE_MM] = ACROSS_SITES[1]
    return out


@dataclass(frozen=True)
class SitePart:
    """One grasp site's part of the gap ``M_b - M_v`` in the mean time of successes.

    ``w`` is the share of a policy's successes that grasped in the site, ``m`` their mean
    time, ``M = (M_b + M_v) / 2``. The site's part is ``mix + rate`` with

        mix  = (w_b - w_v) ((m_b + m_v) / 2 - M)   the policies' different use of the site
        rate = (w_b + w_v) / 2 (m_b - m_v)         their different speed in it

    (a site where one policy has no success: ``rate = 0`` and the other's ``m`` in ``mix``).
    Since ``M_P = sum_k w_Pk m_Pk`` and ``sum_k (w_bk - w_vk) = 0``, the parts of all sites sum
    to ``M_b - M_v`` exactly.
    """

    site: str
    share_baseline: float
    share_vgs: float
    mean_baseline_s: float
    mean_vgs_s: float
    mix_s: float
    rate_s: float

    @property
    def part_s(self) -> float:
        return self.mix_s + self.rate_s


def site_gap(base_sites: np.ndarray, base: pd.DataFrame, vgs_sites: np.ndarray,
             vgs: pd.DataFrame, sites: Sequence[str]) -> list[SitePart]:
    """:class:`SitePart` of each site of ``sites`` (the sites of every success must be among
    them); empty when either policy has no success."""
    ob = base["assembly_success"].to_numpy(bool)
    ov = vgs["assembly_success"].to_numpy(bool)
    if not ob.any() or not ov.any():
        return []
    tb = base["assembly_time_s"].to_numpy(float)[ob]
    tv = vgs["assembly_time_s"].to_numpy(float)[ov]
    sb, sv = np.asarray(base_sites)[ob], np.asarray(vgs_sites)[ov]
    grand = 0.5 * (tb.mean() + tv.mean())
    parts = []
    for site in sites:
        ib, iv = sb == site, sv == site
        wb, wv = float(ib.mean()), float(iv.mean())
        mb = float(tb[ib].mean()) if ib.any() else math.nan
        mv = float(tv[iv].mean()) if iv.any() else math.nan
        if ib.any() and iv.any():
            mix, rate = (wb - wv) * (0.5 * (mb + mv) - grand), 0.5 * (wb + wv) * (mb - mv)
        else:
            mix, rate = (wb - wv) * ((mb if ib.any() else mv if iv.any() else 0.0) - grand), 0.0
        parts.append(SitePart(site, wb, wv, mb, mv, float(mix), float(rate)))
    return parts


def failed_share_pct(tb: np.ndarray, ob: np.ndarray, tv: np.ndarray, ov: np.ndarray) -> float:
    """The failed attempts' share of the gain in total time [%]:

        100 (F_b - F_v) / (S_b - S_v),

    ``S`` the summed assembly times of all attempts (:func:`total_gain_pct`), ``F`` those of
    the failed ones (until given up; a missed grasp costs none). NaN when ``S_b = S_v``.
    """
    sb, sv = float(np.nansum(tb)), float(np.nansum(tv))
    fb, fv = float(np.nansum(tb[~ob])), float(np.nansum(tv[~ov]))
    return 100.0 * (fb - fv) / (sb - sv) if sb != sv else math.nan


def both_within(base: pd.DataFrame, other: pd.DataFrame, limit_mm: float = ALONG_SITE_EDGES_MM[0]
                ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Copies of two tables of the same scenes (sorted by ``index``) in which only the scenes
    where both policies grasped within ``+-limit_mm`` along the axis keep their successes: a
    gain on them (:func:`efficiency_gain`) is the gain restricted to those scenes, and its
    paired bootstrap resamples all scenes, so the number of such scenes varies as it should."""
    base, other = base.sort_values("index").copy(), other.sort_values("index").copy()
    keep = ((np.abs(base["grasp_offset_mm"].to_numpy(float)) < limit_mm)
            & (np.abs(other["grasp_offset_mm"].to_numpy(float)) < limit_mm))
    for t in (base, other):
        t["assembly_success"] = t["assembly_success"].to_numpy(bool) & keep
    return base, other


# -- regret against the centre heuristic ---------------------------------------------------------

REGRET_PARTS = ("re-searches", "flank pixels", "along-axis offset")


@dataclass(frozen=True)
class Regret:
    """VGS's regret against the centre heuristic on the same scenes.

    On the ``n`` scenes both assembled, ``d_i = t_vgs,i - t_centre,i`` and the regret
    ``R = (1/n) sum_i d_i`` [s]. Its parts split those scenes into three disjoint classes and
    give each ``(1/n) sum_{i in class} d_i``, so they sum to ``R``:

    * re-searches: VGS made more new searches than the centre (``retries``);
    * flank pixels: the others where VGS's pixel lay ``ACROSS_SITE_MM`` or more beside the
      axis (``|across_mm|``; None when the table does not hold it);
    * along-axis offset: the rest, VGS's pixel on the axis and no extra search: what its
      offset along the axis costs (plus the scenes' noise). Without ``across_mm`` it holds the
      flank pixels' scenes too.

    Intervals: percentile, paired bootstrap over the scenes both assembled. ``total_pct``:
    ``100 (S_vgs - S_centre) / S_centre`` on the total time of all tests, minus the gain of
    :func:`efficiency_gain` with its paired-bootstrap interval. ``parts`` maps each part to
    ``(value, low, high, scenes)``.
    """

    n: int
    mean_s: float
    low: float
    high: float
    parts: dict[str, tuple[float, float, float, int] | None]
    total_pct: Gain
    failures_vgs: int
    failures_center: int


def regret(center: pd.DataFrame, vgs: pd.DataFrame, resamples: int = BOOTSTRAP_RESAMPLES,
           seed: int = 0) -> Regret:
    """:class:`Regret` of ``vgs`` against ``center``, two tables of the same scenes."""
    c, v = center.sort_values("index"), vgs.sort_values("index")
    # The gain of VGS over the centre in total time, 100 (S_c - S_v) / S_c, is minus the regret.
    g = efficiency_gain(c, v, measure=TOTAL_GAIN, resamples=resamples, seed=seed)
    t_pct = Gain(-g.value, -g.high, -g.low, g.paired, g.n)
    tc, oc = time_arrays(c)
    tv, ov = time_arrays(v)
    both = oc & ov
    fails = int((~ov).sum()), int((~oc).sum())
    if not both.any():
        return Regret(0, math.nan, math.nan, math.nan, {}, t_pct, *fails)
    d = (tv - tc)[both]
    research = (v["retries"].to_numpy(float) > c["retries"].to_numpy(float))[both]
    sites = across_sites(v)
    flank = (None if sites is None else (sites == ACROSS_SITES[1])[both] & ~research)
    along = ~research if flank is None else ~research & ~flank
    masks = {"re-searches": research, "flank pixels": flank, "along-axis offset": along}
    # Fewer than MIN_SUCCESSES scenes both assembled: the values without intervals.
    rng = np.random.default_rng(seed)
    idx = (rng.integers(d.size, size=(resamples, d.size)) if d.size >= MIN_SUCCESSES
           else None)

    def interval(x: np.ndarray) -> tuple[float, float]:
        if idx is None:
            return math.nan, math.nan
        lo, hi = np.percentile(x[idx].mean(axis=1), [2.5, 97.5])
        return float(lo), float(hi)

    parts: dict[str, tuple[float, float, float, int] | None] = {}
    for name, mask in masks.items():
        if mask is None:
            parts[name] = None
            continue
        dm = np.where(mask, d, 0.0)
        parts[name] = (float(dm.mean()), *interval(dm), int(mask.sum()))
    return Regret(int(d.size), float(d.mean()), *interval(d), parts, t_pct, *fails)


# -- across training runs: the crossed bootstrap and the field's statistics ---------------------


def crossed_interval(stat: Callable[[np.ndarray, np.ndarray], float], runs: int, scenes: int,
                     resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0
                     ) -> tuple[float, float]:
    """Percentile 95 % interval of ``stat(drawn runs, drawn scenes)`` under the crossed
    bootstrap of ``vgs seeds``: each replicate draws ``runs`` training runs with replacement
    and **one** set of ``scenes`` test scenes with replacement, shared by every drawn run (runs
    and scenes are crossed factors: every run met the same scenes). NaN replicates are dropped.
    """
    rng = np.random.default_rng(seed)
    out = np.empty(resamples)
    for b in range(resamples):
        r = rng.integers(runs, size=runs)
        i = rng.integers(scenes, size=scenes)
        out[b] = stat(r, i)
    out = out[np.isfinite(out)]
    if not out.size:
        return math.nan, math.nan
    low, high = np.percentile(out, [2.5, 97.5])
    return float(low), float(high)


def iqm(values: np.ndarray) -> float:
    """Interquartile mean: the mean of the values left when ``floor(n / 4)`` are cut from each
    end of the sorted values (``scipy.stats.trim_mean(x, 0.25)``, the measure of Agarwal et
    al. 2021); NaN without values."""
    x = np.sort(np.asarray(values, dtype=float).ravel())
    x = x[np.isfinite(x)]
    if not x.size:
        return math.nan
    cut = int(0.25 * x.size)
    return float(x[cut:x.size - cut].mean())


def win_matrix(tv: np.ndarray, ov: np.ndarray, to: np.ndarray, oo: np.ndarray) -> np.ndarray:
    """Per scene, 1 where VGS assembled faster than the other policy, 1/2 on a tie and 0
    otherwise; a failed test is slower than any success, two failures tie."""
    a = np.where(ov, tv, np.inf)
    b = np.where(oo, to, np.inf)
    return np.where(a < b, 1.0, np.where(a == b, 0.5, 0.0))


def improvement_probability(wins: np.ndarray, resamples: int = BOOTSTRAP_RESAMPLES,
                            seed: int = 0) -> tuple[float, float, float]:
    """``P(VGS faster)`` on a random paired scene of a random training run, the mean of
    ``wins`` (runs x scenes, :func:`win_matrix`), with the crossed-bootstrap 95 % interval."""
    wins = np.atleast_2d(np.asarray(wins, dtype=float))
    low, high = crossed_interval(lambda r, i: float(wins[np.ix_(r, i)].mean()), *wins.shape,
                                 resamples=resamples, seed=seed)
    return float(wins.mean()), low, high


def iqm_interval(times: np.ndarray, ok: np.ndarray, resamples: int = BOOTSTRAP_RESAMPLES,
                 seed: int = 0) -> tuple[float, float, float]:
    """IQM of the assembly times of the successes pooled over training runs (``times`` and
    ``ok``: runs x scenes), with the crossed-bootstrap 95 % interval."""
    times = np.atleast_2d(np.asarray(times, dtype=float))
    ok = np.atleast_2d(np.asarray(ok, dtype=bool))
    t = np.where(ok, times, np.nan)
    low, high = crossed_interval(lambda r, i: iqm(t[np.ix_(r, i)]), *t.shape,
                                 resamples=resamples, seed=seed)
    return iqm(t), low, high


def mean_gain(pairs: list[tuple[pd.DataFrame, pd.DataFrame]],
              resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0,
              measure: Measure = MEAN_GAIN) -> tuple[float, float, float]:
    """Mean over training runs of the gain, with the crossed bootstrap's 95 % interval
    (:func:`crossed_interval`: runs and one shared draw of test scenes per replicate).

    Args:
        pairs: ``(baseline table, VGS table)`` of each training run, on the same test scenes
            (the same episode indices).
        resamples: Bootstrap resamples.
        seed: Seed of the resampling.
        measure: The gain of one run on given scenes: ``MEAN_GAIN`` (mean of the successes)
            or ``TOTAL_GAIN`` (total time of all attempts), :mod:`vgs.analysis.stats`.

    Returns:
        ``(mean gain, low, high)`` in percent; the interval is NaN when a run has fewer than
        ``measure.min_successes`` successes for either policy.

    Raises:
        ConfigError: If the tables do not hold the same episode indices.
    """
    indices = {tuple(np.sort(t["index"].to_numpy())) for pair in pairs for t in pair}
    if len(indices) > 1:
        raise ConfigError("seeds", "the training runs' tables do not hold the same test "
                                   "episodes; the crossed bootstrap needs shared scenes")
    if any(measure.column not in t.columns for pair in pairs for t in pair):
        return math.nan, math.nan, math.nan  # tables written without that column
    arrays = [(*time_arrays(b, measure.column), *time_arrays(v, measure.column))
              for b, v in pairs]
    gains = [measure(*a) for a in arrays]
    value = float(np.mean(gains)) if gains else math.nan
    if (not math.isfinite(value)
            or min(min(a[1].sum(), a[3].sum()) for a in arrays) < measure.min_successes):
        return value, math.nan, math.nan

    def stat(runs: np.ndarray, i: np.ndarray) -> float:
        return sum(measure(*(x[i] for x in arrays[s])) for s in runs) / len(arrays)

    low, high = crossed_interval(stat, len(arrays), len(arrays[0][0]), resamples, seed)
    return value, low, high
