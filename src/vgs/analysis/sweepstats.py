"""The statistics of a grasp-position sweep: per offset the success rate and the time spread
(population standard deviation, :func:`vgs.analysis.stats.population_std`), and the paired
comparison with the centre grasp on the same scenes (bootstrap intervals, the time-vs-offset
slope, left against right). :mod:`vgs.experiments.sweep` writes them to ``summary.json``."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vgs.analysis.stats import BOOTSTRAP_RESAMPLES, population_std


def _stat(values: np.ndarray, fn: Any) -> float | None:
    return float(fn(values)) if values.size else None


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per offset: trials, success rate and the mean/std/min/max time of successful trials."""
    out = []
    for offset in sorted({r["offset_mm"] for r in rows}):
        group = [r for r in rows if r["offset_mm"] == offset]
        times = np.array([r["assembly_time_s"] for r in group if r["assembly_success"]],
                         dtype=float)
        out.append({
            "offset_mm": offset,
            "n": len(group),
            "successes": int(times.size),
            "success_rate": times.size / len(group),
            "time_mean_s": _stat(times, np.mean),
            "time_std_s": _stat(times, population_std),
            "time_min_s": _stat(times, np.min),
            "time_max_s": _stat(times, np.max),
            "adjustments_mean": float(np.mean([r["adjustments"] for r in group])),
            "retry_rate": float(np.mean([r.get("retries", 0) > 0 for r in group])),
            "peg_lost": sum(r["failure_reason"] == "peg_lost" for r in group),
            "time_align_mean_s": _stat(np.array([r["time_align_s"] for r in group
                                                 if r["assembly_success"]], dtype=float), np.mean),
        })
    return out


def _bootstrap_ci(stat: Any, scenes: np.ndarray, resamples: int,
                  rng: np.random.Generator) -> tuple[float, float]:
    """95 % percentile interval of ``stat(scene_sample)`` over scenes drawn with replacement."""
    values = [stat(rng.choice(scenes, size=scenes.size, replace=True)) for _ in range(resamples)]
    values = np.array([v for v in values if math.isfinite(v)])
    if values.size < resamples // 2:
        return math.nan, math.nan
    return float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))


@dataclass(frozen=True)
class PairedRows:
    """The rows of a paired sweep indexed by (scene, offset).

    Attributes:
        table: ``(trial, offset_mm) -> row``.
        offsets: The sweep's offsets [mm], ascending.
        scenes: The scene (``trial``) numbers, ascending.
    """

    table: dict[tuple[int, float], dict[str, Any]]
    offsets: list[float]
    scenes: np.ndarray

    @classmethod
    def of(cls, rows: Sequence[dict[str, Any]]) -> PairedRows:
        return cls({(int(r["trial"]), round(float(r["offset_mm"]), 6)): r for r in rows},
                   sorted({round(float(r["offset_mm"]), 6) for r in rows}),
                   np.array(sorted({int(r["trial"]) for r in rows})))

    def ok_time(self, trial: int, offset: float, key: str) -> float:
        """Column ``key`` of a successful trial, NaN for a failed or missing one."""
        r = self.table.get((trial, offset))
        return float(r[key]) if r is not None and r["assembly_success"] else math.nan


def paired_analysis(rows: Sequence[dict[str, Any]], resamples: int = BOOTSTRAP_RESAMPLES,
                    seed: int = 0) -> dict[str, Any]:
    """Scene-by-scene comparisons of a paired sweep (every offset on the same scenes).

    - ``vs_center`` (:func:`vs_center`): per offset, the mean over scenes where both succeeded
      of ``T(offset) - T(0)`` (total and alignment time), with a 95 % bootstrap interval over
      scenes; needs the offset 0 in the sweep.
    - ``slope`` (:func:`slopes`): least-squares slope of the assembly time (and of the
      alignment time) against |offset| over the successful rows, s per mm, with a 95 % interval
      from resampling whole scenes (all offsets of a drawn scene together).
    - ``symmetry`` (:func:`symmetry`): per |offset| > 0, success and mean time at +c and -c,
      each with its 95 % interval (Wilson for success, bootstrap over scenes for the time).

    The three draw from one generator in this order, so a summary re-derives exactly.

    Args:
        rows: Sweep rows with a ``trial`` column (the scene).
        resamples: Bootstrap resamples.
        seed: Seed of the resampling.
    """
    rng = np.random.default_rng(seed)
    paired = PairedRows.of(rows)
    return {"scenes": int(paired.scenes.size),
            "vs_center": vs_center(paired, resamples, rng),
            "slope": slopes(paired, resamples, rng),
            "symmetry": symmetry(paired, resamples, rng)}


def vs_center(paired: PairedRows, resamples: int, rng: np.random.Generator
              ) -> list[dict[str, Any]]:
    """Per offset, the mean paired difference to the centre grasp (:func:`paired_analysis`)."""
    scenes, out = paired.scenes, []
    if 0.0 not in paired.offsets:
        return out
    for o in paired.offsets:
        if o == 0.0:
            continue
        entry: dict[str, Any] = {"offset_mm": o}
        for key, name in (("assembly_time_s", "time"), ("time_align_s", "align")):
            diff = np.array([paired.ok_time(t, o, key) - paired.ok_time(t, 0.0, key)
                             for t in scenes])
            lookup = dict(zip(scenes.tolist(), diff.tolist(), strict=True))

            def mean_diff(sample: np.ndarray, lookup: dict[int, float] = lookup) -> float:
                v = np.array([lookup[int(t)] for t in sample])
                v = v[np.isfinite(v)]
                return float(v.mean()) if v.size else math.nan

            lo, hi = _bootstrap_ci(mean_diff, scenes, resamples, rng)
            entry[f"{name}_diff_s"] = mean_diff(scenes)
            entry[f"{name}_diff_ci_s"] = [lo, hi]
            entry["pairs"] = int(np.isfinite(diff).sum())
        out.append(entry)
    return out


def slopes(paired: PairedRows, resamples: int, rng: np.random.Generator) -> dict[str, Any]:
    """The assembly and alignment times' slopes against |offset| (:func:`paired_analysis`)."""
    out: dict[str, Any] = {}
    for key, name in (("assembly_time_s", "time"), ("time_align_s", "align")):
        def slope(sample: np.ndarray, key: str = key) -> float:
            x, y = [], []
            for t in sample:
                for o in paired.offsets:
                    v = paired.ok_time(int(t), o, key)
                    if math.isfinite(v):
                        x.append(abs(o))
                        y.append(v)
            if len(set(x)) < 2:
                return math.nan
            return float(np.polyfit(np.array(x), np.array(y), 1)[0])

        lo, hi = _bootstrap_ci(slope, paired.scenes, resamples, rng)
        out[f"{name}_s_per_mm"] = slope(paired.scenes)
        out[f"{name}_ci_s_per_mm"] = [lo, hi]
    return out


def symmetry(paired: PairedRows, resamples: int, rng: np.random.Generator
             ) -> list[dict[str, Any]]:
    """Success and mean time at +c against -c (:func:`paired_analysis`)."""
    scenes, out = paired.scenes, []
    for o in paired.offsets:
        if o <= 0.0 or -o not in paired.offsets:
            continue
        entry: dict[str, Any] = {"abs_offset_mm": o}
        for side, v in (("plus", o), ("minus", -o)):
            group = [paired.table[(int(t), v)] for t in scenes if (int(t), v) in paired.table]
            k, n = sum(bool(r["assembly_success"]) for r in group), len(group)
            entry[f"{side}_success"] = [k, n]
            entry[f"{side}_success_ci"] = list(wilson_interval(k, n))

            def mean_time(sample: np.ndarray, v: float = v) -> float:
                vals = np.array([paired.ok_time(int(t), v, "assembly_time_s") for t in sample])
                vals = vals[np.isfinite(vals)]
                return float(vals.mean()) if vals.size else math.nan

            entry[f"{side}_time_s"] = mean_time(scenes)
            entry[f"{side}_time_ci_s"] = list(_bootstrap_ci(mean_time, scenes, resamples, rng))
        out.append(entry)
    return out


def wilson_interval(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score 95 % interval of a success rate k / n."""
    if n == 0:
        return math.nan, math.nan
    p = k / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)
