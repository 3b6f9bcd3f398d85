"""What VGS's gain over the baseline is made of, and its regret against the centre heuristic,
per condition: the sections of ``vgs report`` and ``vgs seeds`` (issue 52).

The statistics are :mod:`vgs.analysis.stats` (:func:`~vgs.analysis.stats.phase_gap`,
:func:`~vgs.analysis.stats.site_gap`, :func:`~vgs.analysis.stats.failed_share_pct`,
:func:`~vgs.analysis.stats.both_within`, :func:`~vgs.analysis.stats.regret`); this module
gathers the tables of one condition per training run, averages the runs' parts (each run weighs
the same, as the gains of ``vgs seeds``; a mean of exact splits is an exact split of the mean
gap) and writes the tables into a :class:`~vgs.analysis.reportdoc.Doc`. docs/evaluation.md
defines every number.

The centre heuristic's tests come from the reproduction itself (``eval/center/``) or from
another results folder (``--center DIR``, :func:`check_center`), which must hold the same test
scenes: the same root seed and, index by index, the same scene seeds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pandas as pd

from vgs.analysis.reportdoc import Doc
from vgs.analysis.reportfigures import LEARNED
from vgs.analysis.stats import (
    ACROSS_SITES,
    ALONG_SITE_EDGES_MM,
    ALONG_SITES,
    REGRET_PARTS,
    Regret,
    SitePart,
    across_sites,
    along_sites,
    both_within,
    failed_share_pct,
    mean_gain,
    phase_gap,
    phase_variance_shares,
    regret,
    site_gap,
    t_interval,
    time_arrays,
    total_gain_pct,
)
from vgs.config import CONDITIONS
from vgs.errors import ConfigError


@dataclass(frozen=True)
class Makeup:
    """The make-up of VGS's gain on one condition, averaged over its training runs.

    Attributes:
        condition: The test condition.
        runs: The training runs' names.
        phases: Per phase the part of the gap in the mean time of successes [s] (``gap``: the
            gap itself, ``other``: what the phases do not hold).
        variance: Per policy (baseline, vgs), each phase's share of the variance of the
            successes' times (:func:`~vgs.analysis.stats.phase_variance_shares`), mean over
            runs.
        along: Per site along the axis, its part of that gap (:class:`SitePart`).
        across: The same across the axis; None when the tables do not hold ``across_mm``.
        failed_share_pct: Per run, the failed attempts' share of the gain in total time [%].
        total_gain_pct: Per run, the gain in total time [%].
        within: The gain on the mean time of successes on the scenes where both policies
            grasped within +-26 mm along the axis: mean over runs [%] and its 95 % interval
            (crossed bootstrap; one run: the paired bootstrap over its scenes).
        within_phases: The phase split of that restricted gap [s], averaged over runs.
        within_scenes: Per run, the scenes where both grasped within +-26 mm.
        regrets: Per run, VGS's regret against the centre heuristic; None without a centre.
    """

    condition: str
    runs: tuple[str, ...]
    phases: dict[str, float]
    variance: dict[str, dict[str, float]]
    along: list[SitePart]
    across: list[SitePart] | None
    failed_share_pct: tuple[float, ...]
    total_gain_pct: tuple[float, ...]
    within: tuple[float, float, float]
    within_phases: dict[str, float]
    within_scenes: tuple[int, ...]
    regrets: tuple[Regret, ...] | None


def condition_pairs(df: pd.DataFrame, condition: str
                    ) -> list[tuple[str, pd.DataFrame, pd.DataFrame]]:
    """``(training run, baseline table, VGS table)`` of every run evaluated with both policies
    on ``condition``, each sorted by ``index`` (tables without ``train_run``: one run, ``-``)."""
    part = df[df["condition"] == condition]
    runs = sorted(set(part["train_run"])) if "train_run" in part.columns else ["-"]
    pairs = []
    for run in runs:
        mine = part if run == "-" else part[part["train_run"] == run]
        base, vgs = (mine[mine["policy"] == p].sort_values("index") for p in LEARNED)
        if len(base) and len(vgs) and list(base["index"]) == list(vgs["index"]):
            pairs.append((str(run), base, vgs))
    return pairs


def check_center(center: pd.DataFrame, tests: pd.DataFrame, source: Path) -> pd.DataFrame:
    """The centre heuristic's test episodes of ``center`` (a results folder's tables, read
    from ``source``), checked against the scenes of ``tests`` (the learned policies' tables).

    Raises:
        ConfigError: If ``center`` holds no centre evaluation, or one of its conditions was
            tested on other scenes than ``tests`` (another root seed, other episode indices
            or other scene seeds).
    """
    center = center[center["policy"] == "center"]
    if center.empty:
        raise ConfigError("center", f"{source} holds no centre-heuristic evaluation "
                                    "(eval/center/<condition>/)")
    for condition in sorted(set(center["condition"]) & set(tests["condition"])):
        mine = center[center["condition"] == condition].sort_values("index")
        theirs = (tests[tests["condition"] == condition].drop_duplicates("index")
                  .sort_values("index"))
        same = (list(mine["index"]) == list(theirs["index"])
                and list(mine["seed"]) == list(theirs["seed"])
                and set(mine["root_seed"].astype(str)) == set(theirs["root_seed"].astype(str)))
        if not same:
            raise ConfigError("center", f"{source}: its {condition} tests are not the same scenes "
                                        "(root seed, episode indices or scene seeds differ); "
                                        "evaluate the centre with the same reproduce.eval_seed "
                                        "and eval.episodes")
    return center


def center_of(df: pd.DataFrame, condition: str, center: pd.DataFrame | None
              ) -> pd.DataFrame | None:
    """The centre heuristic's tests of ``condition``: from ``center`` when given, else from
    ``df`` (a reproduction that evaluated it); None when neither holds them."""
    source = center if center is not None else df
    mine = source[(source["policy"] == "center") & (source["condition"] == condition)]
    return mine.sort_values("index") if len(mine) else None


def _mean_dicts(dicts: list[dict[str, float]]) -> dict[str, float]:
    keys = list(dict.fromkeys(k for d in dicts for k in d))
    return {k: float(np.mean([d.get(k, 0.0) for d in dicts])) for k in keys}


def _mean_parts(runs: list[list[SitePart]]) -> list[SitePart]:
    """Each site's fields averaged over the runs (its means over the runs with successes
    there; the parts, hence their sum, as plain means)."""
    out = []
    for parts in zip(*runs, strict=True):
        values = {}
        for f in fields(SitePart):
            if f.name == "site":
                continue
            x = np.array([getattr(p, f.name) for p in parts], float)
            values[f.name] = (float(np.nanmean(x)) if np.isfinite(x).any() else math.nan)
        out.append(SitePart(parts[0].site, **values))
    return out


def gain_makeup(condition: str, pairs: list[tuple[str, pd.DataFrame, pd.DataFrame]],
                center: pd.DataFrame | None = None) -> Makeup:
    """:class:`Makeup` of ``pairs`` (:func:`condition_pairs`), with VGS's regret against
    ``center`` when given."""
    phases, along, across, within_phases = [], [], [], []
    variance: dict[str, list[dict[str, float]]] = {p: [] for p in LEARNED}
    failed, totals, scenes, within_pairs = [], [], [], []
    has_across = True
    for _, base, vgs in pairs:
        phases.append(phase_gap(base, vgs))
        for policy, table in zip(LEARNED, (base, vgs), strict=True):
            variance[policy].append(phase_variance_shares(table))
        along.append(site_gap(along_sites(base["grasp_offset_mm"]), base,
                              along_sites(vgs["grasp_offset_mm"]), vgs, ALONG_SITES))
        sb, sv = across_sites(base), across_sites(vgs)
        has_across = has_across and sb is not None and sv is not None
        if has_across:
            across.append(site_gap(sb, base, sv, vgs, ACROSS_SITES))
        arrays = (*time_arrays(base), *time_arrays(vgs))
        failed.append(failed_share_pct(*arrays))
        totals.append(total_gain_pct(*arrays))
        wb, wv = both_within(base, vgs)
        scenes.append(int(np.sum((np.abs(wb["grasp_offset_mm"].to_numpy(float))
                                  < ALONG_SITE_EDGES_MM[0])
                                 & (np.abs(wv["grasp_offset_mm"].to_numpy(float))
                                    < ALONG_SITE_EDGES_MM[0]))))
        within_pairs.append((wb, wv))
        within_phases.append(phase_gap(wb, wv))
    regrets = None
    if center is not None and len(center):
        regrets = tuple(regret(center, vgs) for _, _, vgs in pairs
                        if list(center["index"]) == list(vgs["index"]))
    return Makeup(condition, tuple(r for r, _, _ in pairs), _mean_dicts(phases),
                  {p: _mean_dicts([v for v in variance[p] if v]) for p in LEARNED},
                  _mean_parts(along), _mean_parts(across) if has_across else None,
                  tuple(failed), tuple(totals), mean_gain(within_pairs),
                  _mean_dicts([p for p in within_phases if p]), tuple(scenes), regrets or None)


def makeups(df: pd.DataFrame, center: pd.DataFrame | None = None) -> list[Makeup]:
    """:func:`gain_makeup` of every condition of ``df`` with both learned policies."""
    out = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        pairs = condition_pairs(df, condition)
        if pairs:
            out.append(gain_makeup(condition, pairs, center_of(df, condition, center)))
    return out


# -- the document --------------------------------------------------------------------------------


def _s(value: float, digits: int = 2) -> str:
    return "-" if not math.isfinite(value) else f"{value:+.{digits}f}"


def _f(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{value:.1f}"


def _pct(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{100 * value:.0f} %"


def _range(values: tuple[float, ...], unit: str = " %") -> str:
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return "n/a"
    if len(v) == 1:
        return f"{v[0]:.0f}{unit}"
    return f"{np.mean(v):.0f}{unit} (runs {min(v):.0f} to {max(v):.0f}{unit})"


def write_makeup(doc: Doc, items: list[Makeup], command: str) -> None:
    """The section "What the gain is made of": the phase split of every condition in one
    table, then per condition the split by grasp site along (and across) the axis, the failed
    attempts' share of the gain in total time and the gain on scenes grasped within +-26 mm."""
    if not items:
        return
    runs = max(len(m.runs) for m in items)
    over = f", mean over {runs} training runs" if runs > 1 else ""
    doc.h(2, "What the gain is made of")
    doc.p(f"Made by `{command}` (docs/evaluation.md, \"What the gain is made of\", defines each "
          f"number){over}. The gap is the baseline's mean time of successes less VGS's [s]; "
          "its rows sum to it.")
    keys = list(dict.fromkeys(k for m in items for k in m.phases if k not in ("gap", "other")))
    if any(abs(m.phases.get("other", 0.0)) > 1e-6 for m in items):
        keys.append("other")

    def cell(m: Makeup, key: str) -> str:
        value, gap = m.phases.get(key, math.nan), m.phases.get("gap", math.nan)
        share = f" ({100 * value / gap:.0f} %)" if math.isfinite(value) and gap else ""
        return _s(value) + share

    rows = [[k, *(cell(m, k) for m in items)] for k in [*keys, "gap"]]
    rows[-1][0] = "**gap**"
    doc.table(["phase", *(f"{m.condition} [s] (share of the gap)" for m in items)], rows)
    doc.p("Each phase's share of the variance of the successes' times, cov(t_phase, T) / "
          "var(T), baseline / VGS (the shares sum to 100 %):")
    doc.table(["phase", *(m.condition for m in items)],
              [[k, *(" / ".join(_pct(m.variance.get(p, {}).get(k, math.nan)) for p in LEARNED)
                     for m in items)] for k in keys if k != "other"])
    head = ["site", "share of successes, base / VGS", "mean time [s], base / VGS",
            "mix [s]", "rate [s]", "part of the gap [s]"]
    for m in items:
        for label, parts in (("along the axis (|grasp_offset_mm|)", m.along),
                             ("across the axis (|across_mm|)", m.across)):
            if parts is None:
                doc.p(f"**{m.condition}**, across the axis: unavailable (these tables hold no "
                      "`across_mm`; `vgs grasp-sites DIR` recomputes it by replaying the "
                      "scenes).")
                continue
            rows = [[p.site, f"{_pct(p.share_baseline)} / {_pct(p.share_vgs)}",
                     f"{_f(p.mean_baseline_s)} / {_f(p.mean_vgs_s)}",
                     _s(p.mix_s), _s(p.rate_s), _s(p.part_s)] for p in parts]
            rows.append(["**sum**", "", "", _s(sum(p.mix_s for p in parts)),
                         _s(sum(p.rate_s for p in parts)), _s(sum(p.part_s for p in parts))])
            doc.p(f"**{m.condition}**, by where each policy grasped {label}:")
            doc.table(head, rows)
        value, low, high = m.within
        interval = (f" [{low:+.1f}, {high:+.1f}]" if math.isfinite(low) else "")
        align = m.within_phases.get("align", math.nan)
        doc.p(f"**{m.condition}**: the failed attempts carry {_range(m.failed_share_pct)} of "
              f"the gain in total time ({_range(m.total_gain_pct)}). On the scenes where both "
              f"policies grasped within +-26 mm along the axis ({_range(m.within_scenes, '')} "
              f"of them) the gain on the mean time of successes is "
              f"{'n/a' if not math.isfinite(value) else f'{value:+.1f} %'}{interval}, a gap "
              f"of {_s(m.within_phases.get('gap', math.nan))} s of which the alignment "
              f"carries {_s(align)} s and the search "
              f"{_s(m.within_phases.get('search', math.nan))} s.")


def write_regret(doc: Doc, items: list[Makeup], command: str) -> None:
    """The section "Regret against the centre heuristic": per condition and training run,
    VGS's extra time on the scenes both assembled with its parts, its regret in total time
    and both policies' failures; with several runs a mean row with Student's t interval."""
    items = [m for m in items if m.regrets]
    if not items:
        return
    doc.h(2, "Regret against the centre heuristic")
    doc.p(f"Made by `{command}`. Regret: VGS's time less the centre heuristic's on the same "
          "scenes, mean over the scenes both assembled [s] (paired bootstrap 95 % interval), "
          "split into three disjoint classes of those scenes that sum to it: re-searches "
          "(VGS searched anew more often than the centre), flank pixels (the others where "
          "VGS's pixel lay 5 mm or more beside the axis) and along-axis offset (the rest: its "
          "pixel on the axis, no extra search; with the flank pixels' scenes when `across_mm` "
          "is not recorded). In total time: 100 (S_VGS - S_centre) / S_centre over all tests, "
          "failed attempts included.")
    head = ["condition", "run", "scenes both assembled", "regret [s]",
            *(f"{p} [s] (scenes)" for p in REGRET_PARTS), "regret in total time",
            "failures, VGS / centre"]
    rows = []
    for m in items:
        for run, r in zip(m.runs, m.regrets or (), strict=False):
            parts = [("n/a" if r.parts.get(p) is None else
                      f"{_s(r.parts[p][0])} ({r.parts[p][3]})") for p in REGRET_PARTS]
            rows.append([m.condition, run, str(r.n),
                         _s(r.mean_s) + (f" [{_s(r.low)}, {_s(r.high)}]"
                                         if math.isfinite(r.low) else ""), *parts,
                         r.total_pct.text(), f"{r.failures_vgs} / {r.failures_center}"])
        regrets = m.regrets or ()
        if len(regrets) > 1:
            means = np.array([r.mean_s for r in regrets])
            lo, hi = t_interval(means)
            parts = []
            for p in REGRET_PARTS:
                vals = [r.parts[p][0] for r in regrets if r.parts.get(p) is not None]
                parts.append(_s(float(np.mean(vals))) if vals else "n/a")
            totals = np.array([r.total_pct.value for r in regrets])
            tlo, thi = t_interval(totals)
            rows.append([m.condition, "**mean**", "", f"{_s(means.mean())}, t [{_s(lo)}, "
                         f"{_s(hi)}]", *parts, f"{totals.mean():+.2f} %, t [{tlo:+.2f}, "
                         f"{thi:+.2f}]", f"{np.mean([r.failures_vgs for r in regrets]):.1f} / "
                         f"{np.mean([r.failures_center for r in regrets]):.1f}"])
    doc.table(head, rows)


def write_references(doc: Doc, df: pd.DataFrame, command: str) -> None:
    """The section "Against the reference policies": each learned policy of each training run
    against each reference policy evaluated in the same folder (``center``, ``com-oracle``,
    ...) on the same scenes, by :func:`vgs.analysis.stats.regret`: the mean difference of the
    times on the scenes both assembled (learned less reference, paired bootstrap 95 %
    interval), the difference in total time over all tests, failed attempts included, and the
    assemblies of each. Nothing is written when the folder holds no reference policy."""
    rows = []
    oracle = "com-oracle" in set(df["policy"])
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        part = df[df["condition"] == condition]
        references = sorted(set(part["policy"]) - set(LEARNED))
        pairs = condition_pairs(df, condition)
        for ref in references:
            mine = part[part["policy"] == ref].sort_values("index")
            for run, *tables in pairs:
                for policy, table in zip(LEARNED, tables, strict=True):
                    if list(table["index"]) != list(mine["index"]):
                        continue
                    r = regret(mine, table)
                    diff = _s(r.mean_s) + (f" [{_s(r.low)}, {_s(r.high)}]"
                                           if math.isfinite(r.low) else "")
                    rows.append([condition, ref, f"{policy} {run}".strip(" -"), str(r.n), diff,
                                 r.total_pct.text(),
                                 f"{len(table) - r.failures_vgs}/{len(table)} / "
                                 f"{len(mine) - r.failures_center}/{len(mine)}"])
    if not rows:
        return
    doc.h(2, "Against the reference policies")
    doc.p(f"Made by `{command}`. Each learned policy against each reference policy on the same "
          "test scenes: its time less the reference's, mean over the scenes both assembled [s] "
          "(paired bootstrap 95 % interval; negative: the learned policy is faster); the same "
          "in total time over all tests, failed attempts included, "
          "100 (S_learned - S_reference) / S_reference; and the assemblies of each."
          + (" `com-oracle` grasps at the true centre of mass (ground truth, analysis only)."
             if oracle else ""))
    doc.table(["condition", "reference", "learned policy", "scenes both assembled",
               "time difference [s]", "difference in total time",
               "assembled, learned / reference"], rows)
