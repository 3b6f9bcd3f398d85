"""Across training seeds: the efficiency gain of each trained pair and their mean.

One training seed gives one baseline and one VGS network; the gain measured on its test
episodes carries the test-episode noise (the paired bootstrap of :mod:`vgs.analysis.report`)
but not the spread between training runs, which can be larger (one seed's baseline may learn to
grasp, another's not). ``vgs seeds DIR [DIR ...] --out DEST`` gathers the evaluation tables of
several reproduce folders (or their published copies under ``docs/results``) and writes:

* ``DEST/seeds.csv``: one row per (condition, training run) and one ``mean`` row per condition;
* ``DEST/seeds.md``: a summary (one line per condition, the README's headline) and the same
  as tables per condition, with the commands' folders;
* ``DEST/seeds.png``: the gains with their intervals, per condition, the paper's gain beside.

Statistics. For training run ``s`` the gain is ``g_s = 100 (T_base,s - T_vgs,s) / T_base,s`` on
the mean times of successful assemblies, with the paired bootstrap interval over its test
episodes. The across-seed estimate is the plain mean ``g = (1/S) sum_s g_s`` (each training run
weighs the same, whatever its number of successes). Its 95 % interval comes from a bootstrap
that follows the design: every training run meets the *same* test scenes, so runs and scenes
are crossed factors, and a scene that is hard for one run's policies tends to be hard for the
others'. Each replicate draws ``S`` training runs with replacement and **one** set of test
scenes with replacement, the same for every drawn run (paired: both policies of a run keep the
same scenes), and averages the drawn runs' gains on those scenes; percentile interval over 2000
replicates. (Drawing each run's scenes anew, a nested bootstrap, would treat the shared scenes'
difficulty as independent noise that averages out over runs, and give too narrow an interval.)
With two or three seeds the run level has few distinct draws, so the interval is coarse; the
table also gives the spread between seeds (sample standard deviation of ``g_s``).

The same statistics on the paper's own measure, the total simulated time of all test attempts
(``h_s = 100 (S_base,s - S_vgs,s) / S_base,s``, :func:`vgs.analysis.stats.total_gain_pct`):
the paper's tests all assembled, so there the two measures coincide; here a policy that often
fails pays each failed attempt in ``h_s``, which ``g_s`` does not see.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from vgs.analysis.makeup import (  # noqa: E402
    center_of,
    makeups,
    write_makeup,
    write_regret,
)
from vgs.analysis.palette import GAIN_COLORS, policy_color  # noqa: E402
from vgs.analysis.report import PAPER, load_center, load_results  # noqa: E402
from vgs.analysis.reportdoc import Doc  # noqa: E402
from vgs.analysis.reportfigures import CONDITION_TITLES, LEARNED  # noqa: E402
from vgs.analysis.stats import (  # noqa: E402
    ALIGN_GAIN,
    GAINS,
    MEAN_GAIN,
    SUCCESS_TOTAL_GAIN,
    TOTAL_GAIN,
    efficiency_gain,
    improvement_probability,
    iqm_interval,
    mean_gain,
    sample_std,
    summarize,
    t_interval,
    time_arrays,
    win_matrix,
)
from vgs.columns import rounded  # noqa: E402
from vgs.config import CONDITIONS  # noqa: E402
from vgs.errors import ConfigError  # noqa: E402

# Each gain of stats.GAINS gives the columns <name>_pct, <name>_ci_low, <name>_ci_high, and on
# the mean row <name>_sd_between_seeds, <name>_t_low, <name>_t_high, seeds_with_positive_<name>.


def load_seeds(folders: list[Path]) -> pd.DataFrame:
    """Baseline and VGS test episodes of every training run in ``folders``.

    Adds the column ``source`` (the folder). Reference policies (centre, random) are left out:
    they do not depend on a training seed.

    Raises:
        ConfigError: If a folder has no results, holds no baseline or VGS table, two folders hold
            the same training run on the same condition (one run may be evaluated on some
            conditions in one folder and on others in another), or the folders' test scenes
            differ (another evaluation root seed or number of episodes), so the gains would not
            be comparable.
    """
    if not folders:
        raise ConfigError("seeds", "give at least one results folder")
    frames = []
    owner: dict[tuple[str, str], Path] = {}
    for folder in folders:
        try:
            df = load_results(folder)
        except ConfigError as exc:
            raise ConfigError("seeds", exc.message) from exc
        df = df[df["policy"].isin(LEARNED)].copy()
        if df.empty:
            raise ConfigError("seeds", f"{folder} holds no baseline or VGS evaluation")
        if "train_run" not in df:
            df["train_run"] = "s?"
        for run, condition in sorted(set(zip(df["train_run"], df["condition"], strict=True))):
            if (run, condition) in owner:
                raise ConfigError("seeds", f"training run {run} on the {condition} condition is "
                                           f"in both {owner[run, condition]} and {folder}; "
                                           "give each run and condition once")
            owner[run, condition] = folder
        frames.append(df.assign(source=str(folder)))
    df = pd.concat(frames, ignore_index=True)
    for condition, part in df.groupby("condition"):
        scenes = {(run, str(p["root_seed"].iloc[0]), len(p))
                  for run, p in part.groupby(["train_run", "policy"])}
        roots = {s[1] for s in scenes}
        sizes = {s[2] for s in scenes}
        if len(roots) > 1 or len(sizes) > 1:
            raise ConfigError("seeds", f"{condition}: the folders were evaluated on different "
                                       f"test scenes (root seeds {sorted(roots)}, episodes "
                                       f"{sorted(sizes)}); evaluate them with the same "
                                       "reproduce.eval_seed and eval.episodes")
    return df


def seeds_table(df: pd.DataFrame) -> pd.DataFrame:
    """One row per (condition, training run) and a ``mean`` row per condition."""
    rows: list[dict[str, Any]] = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        part = df[df["condition"] == condition]
        pairs = []
        for run in sorted(set(part["train_run"])):
            mine = part[part["train_run"] == run]
            base, vgs = (mine[mine["policy"] == p] for p in LEARNED)
            if base.empty or vgs.empty:
                continue  # only one of the two policies evaluated: no gain
            pairs.append((base, vgs))
            sb, sv = summarize(base), summarize(vgs)
            row: dict[str, Any] = {
                "condition": condition, "train_run": run, "source": mine["source"].iloc[0],
                "episodes": sb["episodes"],
                "successes_baseline": sb["successes"], "successes_vgs": sv["successes"],
                "grasp_success_baseline": sb["grasp_success_rate"],
                "grasp_success_vgs": sv["grasp_success_rate"],
                "offset_mm_baseline": sb["abs_grasp_offset_mean_mm"],
                "offset_mm_vgs": sv["abs_grasp_offset_mean_mm"],
                "time_mean_s_baseline": sb["time_mean_s"], "time_mean_s_vgs": sv["time_mean_s"],
                "time_std_s_baseline": sb["time_std_s"], "time_std_s_vgs": sv["time_std_s"],
                "time_all_h_baseline": sb["time_all_h"], "time_all_h_vgs": sv["time_all_h"],
                "time_per_assembled_s_baseline": sb["time_per_assembled_s"],
                "time_per_assembled_s_vgs": sv["time_per_assembled_s"],
            }
            for m in GAINS:
                gain = efficiency_gain(base, vgs, measure=m)
                row.update({f"{m.name}_pct": gain.value, f"{m.name}_ci_low": gain.low,
                            f"{m.name}_ci_high": gain.high})
            rows.append(row)
        if not pairs:
            continue
        mine_rows = [r for r in rows if r["condition"] == condition]
        mean_row: dict[str, Any] = {"condition": condition, "train_run": "mean", "source": "",
                                    "episodes": int(sum(r["episodes"] for r in mine_rows))}
        for key in mine_rows[0]:
            if key.endswith(("_baseline", "_vgs")):
                values = [r[key] for r in mine_rows if r[key] is not None]
                mean_row[key] = (int(sum(values)) if key.startswith("successes")
                                 else float(np.mean(values)) if values else None)
        for m in GAINS:
            value, low, high = mean_gain(pairs, measure=m)
            gains = np.array([r[f"{m.name}_pct"] for r in mine_rows], float)
            t_low, t_high = t_interval(gains)
            mean_row.update({f"{m.name}_pct": value, f"{m.name}_ci_low": low,
                             f"{m.name}_ci_high": high,
                             f"{m.name}_t_low": t_low, f"{m.name}_t_high": t_high,
                             f"{m.name}_sd_between_seeds": sample_std(gains),
                             f"seeds_with_positive_{m.name}": int(np.sum(gains > 0))})
        mean_row["seeds"] = len(mine_rows)
        rows.append(mean_row)
    if not rows:
        raise ConfigError("seeds", "no condition has both a baseline and a VGS evaluation")
    return pd.DataFrame(rows)


def plot_seeds(table: pd.DataFrame, path: Path) -> Path:
    """Forest plot: each training run's gains (on the mean of the successes and on the total
    time) and their means, per condition; the paper's gain."""
    conditions = list(dict.fromkeys(table["condition"]))
    runs = sorted(set(table["train_run"]) - {"mean"}) + ["mean"]
    y_of = {run: float(len(runs) - 1 - i) for i, run in enumerate(runs)}
    fig, axes = plt.subplots(1, len(conditions), figsize=(4.2 * len(conditions), 1.8 + 0.5 *
                             len(runs)), sharex=True, sharey=True, squeeze=False)
    for ax, condition in zip(axes[0], conditions, strict=True):
        part = table[table["condition"] == condition]
        for _, row in part.iterrows():
            mean = row["train_run"] == "mean"
            # Upper mark: the mean of the successes; lower: the total time of all tests.
            for key, color, dy in ((MEAN_GAIN.name, "black" if mean else GAIN_COLORS["gain"],
                                    0.12), (TOTAL_GAIN.name, GAIN_COLORS["total_gain"], -0.12)):
                yi = y_of[row["train_run"]] + dy
                if math.isfinite(row[f"{key}_ci_low"]):
                    ax.plot([row[f"{key}_ci_low"], row[f"{key}_ci_high"]], [yi, yi],
                            color=color, lw=2.5 if mean else 1.5)
                t_low = row.get(f"{key}_t_low", math.nan)
                if mean and isinstance(t_low, float) and math.isfinite(t_low):
                    # Student's t interval over the runs, drawn below the bootstrap's
                    ax.errorbar(row[f"{key}_pct"], yi - 0.09, xerr=[[row[f"{key}_pct"] - t_low],
                                [row[f"{key}_t_high"] - row[f"{key}_pct"]]], fmt="none",
                                ecolor=color, elinewidth=1.0, capsize=3, ls="--")
                ax.plot(row[f"{key}_pct"], yi,
                        "D" if mean else ("o" if key == MEAN_GAIN.name else "s"),
                        color=color, ms=7 if mean else 5)
        ax.axvline(0.0, color="gray", lw=0.8)
        paper = PAPER.get(condition, {}).get("gain")
        if paper is not None:
            ax.axvline(paper, color=GAIN_COLORS["paper"], ls="--", lw=1.2)
            ax.text(paper, len(runs) - 0.45, f" paper {paper:+.2f} % (total time)",
                    color=GAIN_COLORS["paper"],
                    fontsize=8, va="center")
        ax.set_ylim(-0.6, len(runs) - 0.2)
        ax.set_title(CONDITION_TITLES.get(condition, condition), fontsize=9)
        ax.set_xlabel("efficiency gain of VGS [%] (95 % intervals)")
    axes[0][0].plot([], [], "o", color=GAIN_COLORS["gain"], label="mean time of successes")
    axes[0][0].plot([], [], "s", color=GAIN_COLORS["total_gain"], label="total time of all tests")
    axes[0][0].plot([], [], "-", color="black", lw=2.5, label="bootstrap interval")
    axes[0][0].errorbar([], [], xerr=[], fmt="none", ecolor="black", capsize=3,
                        label="mean: Student's t interval over runs")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=4)
    axes[0][0].set_yticks(list(y_of.values()), runs)
    axes[0][0].set_ylabel("training run")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _fmt(value: Any, digits: int = 1, suffix: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}f}{suffix}"


def _gain_text(row: pd.Series, key: str = MEAN_GAIN.name) -> str:
    value, low, high = row[f"{key}_pct"], row[f"{key}_ci_low"], row[f"{key}_ci_high"]
    if not math.isfinite(value):
        return "n/a"
    text = f"{value:+.1f} %" if not math.isfinite(low) else (
        f"{value:+.1f} % [{low:+.1f}, {high:+.1f}]")
    t_low, t_high = row.get(f"{key}_t_low", math.nan), row.get(f"{key}_t_high", math.nan)
    if isinstance(t_low, float) and math.isfinite(t_low):
        text += f", t [{t_low:+.1f}, {t_high:+.1f}]"
    return text


def _interval_verdict(mean: pd.Series, key: str) -> str:
    """What the mean gain ``key`` establishes: a claim needs both its intervals (the crossed
    bootstrap and, with two runs or more, Student's t) on one side of zero; where either
    crosses zero the direction is "not established"."""
    low, high = mean[f"{key}_ci_low"], mean[f"{key}_ci_high"]
    t_low, t_high = mean.get(f"{key}_t_low", math.nan), mean.get(f"{key}_t_high", math.nan)
    if not math.isfinite(low):
        return "too few successes for an interval."
    both = f"bootstrap [{low:+.1f}, {high:+.1f}]"
    bounds = [(low, high)]
    if isinstance(t_low, float) and math.isfinite(t_low):
        both += f" and t [{t_low:+.1f}, {t_high:+.1f}]"
        bounds.append((t_low, t_high))
    if all(lo > 0 for lo, _ in bounds):
        return f"its intervals, {both}, lie above zero: VGS faster, established."
    if all(hi < 0 for _, hi in bounds):
        return f"its intervals, {both}, lie below zero: VGS slower here, established."
    return (f"not established: of its intervals, {both}, at least one includes zero.")


def summary_rows(table: pd.DataFrame) -> list[str]:
    """One line per condition: the headline table (the README copies it, a test compares).

    Per training run the assembled counts and the gain on the mean time of successes; over the
    runs the mean gains (crossed bootstrap and, with two or more runs, Student's t interval),
    the mean of the runs' standard deviations of the assembly time, and the paper's gain.
    """
    runs = table[table["train_run"] != "mean"]
    episodes = sorted(set(int(e) for e in runs["episodes"]))
    of = f" of {episodes[0]}" if len(episodes) == 1 else ""
    names = "; ".join(dict.fromkeys(str(r) for r in runs["train_run"]))
    lines = [f"| condition | assembled{of}, baseline / VGS ({names}) | gain per run | mean gain "
             "| gain in alignment, mean | gain in total time, mean | "
             "std [s], baseline / VGS, mean | gain (paper) |",
             "|---|---|---|---|---|---|---|---|"]
    for condition in dict.fromkeys(table["condition"]):
        part = runs[runs["condition"] == condition]
        mean = table[(table["condition"] == condition)
                     & (table["train_run"] == "mean")].iloc[0]
        paper = PAPER.get(condition, {}).get("gain")
        assembled = "; ".join(f"{int(r['successes_baseline'])} / {int(r['successes_vgs'])}"
                              for _, r in part.iterrows())
        per_run = "; ".join(f"{r['gain_pct']:+.1f} %" if math.isfinite(r["gain_pct"])
                            else "n/a" for _, r in part.iterrows())
        lines.append(
            f"| {CONDITION_TITLES.get(condition, condition).split(' (')[0]} | {assembled} | "
            f"{per_run} | {_gain_text(mean)} | {_gain_text(mean, ALIGN_GAIN.name)} | "
            f"{_gain_text(mean, TOTAL_GAIN.name)} | {_fmt(mean['time_std_s_baseline'], 2)} / "
            f"{_fmt(mean['time_std_s_vgs'], 2)} | "
            f"{'n/a' if paper is None else f'{paper:+.2f} %'} |")
    return lines


def seeds_markdown(table: pd.DataFrame, folders: list[Path], dest: Path, figure: str,
                   center: Path | None = None) -> str:
    """The tables of :func:`seeds_table` as Markdown."""
    lines = ["# VGS against the baseline, across training seeds", "",
             "Written by `vgs seeds " + " ".join(str(f) for f in folders) + f" --out {dest}"
             + (f" --center {center}" if center is not None else "") + "` "
             "(module `vgs.analysis.seeds`). Each training run trains one baseline and one "
             "VGS network; both meet the same test scenes. Gain: (T_baseline - T_VGS) / "
             "T_baseline on the mean time of successful assemblies, 95 % interval from the "
             "paired bootstrap over test episodes; the mean row averages the runs' gains, its "
             "interval from the crossed bootstrap (training runs and one shared draw of the "
             "test scenes per replicate: every run met the same scenes), and beside it Student's "
             "t interval over the runs' gains (mean +- t s / sqrt(n); it sees only the spread "
             "between runs, and with few runs it is wide: t = 2.78 for five). The bootstrap "
             "over n runs can only redraw those n values, so for few runs it understates the "
             "spread between runs; the t interval assumes the gains are normal. Gain in total "
             "time: the same on the summed assembly times of all tests, failed attempts included "
             "until given up (the paper's own measure; its tests all assembled); without "
             "failed attempts: the summed times of the successes alone (it compares like with "
             "like only where both policies assemble about as many tests: a policy that "
             "assembles more sums more times); alignment: the gain on "
             "the mean alignment time of the successes, the phase the paper studies.", "",
             "## Summary", ""]
    lines += summary_rows(table) + [""]
    for condition in dict.fromkeys(table["condition"]):
        part = table[table["condition"] == condition]
        paper = PAPER.get(condition, {}).get("gain")
        lines += [f"## {CONDITION_TITLES.get(condition, condition)}", ""]
        lines += ["| training run | assembled, baseline / VGS | grasp success | "
                  "mean grasp offset [mm] | mean time of successes [s] | "
                  "standard deviation [s] | total time of all tests [h] | "
                  "time per assembled peg [s] | gain in total time | "
                  "same, without failed attempts | gain on mean times | "
                  "gain in alignment |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for _, r in part.iterrows():
            run = "**mean**" if r["train_run"] == "mean" else str(r["train_run"])
            lines.append(
                f"| {run} | {r['successes_baseline']} / {r['successes_vgs']} of "
                f"{r['episodes']} | {_fmt(r['grasp_success_baseline'], 2)} / "
                f"{_fmt(r['grasp_success_vgs'], 2)} | {_fmt(r['offset_mm_baseline'])} / "
                f"{_fmt(r['offset_mm_vgs'])} | {_fmt(r['time_mean_s_baseline'])} / "
                f"{_fmt(r['time_mean_s_vgs'])} | {_fmt(r['time_std_s_baseline'], 2)} / "
                f"{_fmt(r['time_std_s_vgs'], 2)} | {_fmt(r['time_all_h_baseline'], 2)} / "
                f"{_fmt(r['time_all_h_vgs'], 2)} | {_fmt(r['time_per_assembled_s_baseline'])} / "
                f"{_fmt(r['time_per_assembled_s_vgs'])} | {_gain_text(r, TOTAL_GAIN.name)} | "
                f"{_gain_text(r, SUCCESS_TOTAL_GAIN.name)} | {_gain_text(r)} | "
                f"{_gain_text(r, ALIGN_GAIN.name)} |")
        mean = part[part["train_run"] == "mean"].iloc[0]
        seeds = int(mean["seeds"])
        verdict = (f"{int(mean['seeds_with_positive_gain'])} of {seeds} training runs give VGS "
                   "the shorter mean time; ")
        if seeds > 1:
            verdict += (f"the gain varies by {_fmt(mean['gain_sd_between_seeds'])} percentage "
                        "points between runs (standard deviation); ")
        else:
            verdict += ("one training run only: its interval covers the test episodes' noise, "
                        "not the spread between training runs; ")
        if seeds == 2:
            verdict += ("two training runs only: the crossed bootstrap draws its runs from two "
                        "values, so its interval understates the spread between runs; ")
        elif seeds == 3:
            verdict += ("three training runs only: the crossed bootstrap draws its runs from "
                        "ten distinct sets, so its interval is coarse; ")
        elif 3 < seeds < 10:
            verdict += (f"{seeds} training runs: the crossed bootstrap redraws these {seeds} "
                        "values only and can understate the spread between runs, so read the "
                        "t interval beside it; ")
        verdict += "the mean gain: " + _interval_verdict(mean, MEAN_GAIN.name)
        verdict += (f" In total time, {int(mean['seeds_with_positive_total_gain'])} of {seeds} "
                    "training runs give VGS the shorter total; the mean gain in total time: "
                    + _interval_verdict(mean, TOTAL_GAIN.name))
        verdict += (f" In the alignment phase, {int(mean['seeds_with_positive_align_gain'])} of "
                    f"{seeds} training runs give VGS the shorter mean; the mean gain: "
                    + _interval_verdict(mean, ALIGN_GAIN.name))
        if paper is not None:
            verdict += (f" The paper reports {paper:+.2f} %, on its total time over 1000 tests "
                        "(none reported failed): the like of our gain in total time.")
        totals = PAPER.get(condition, {}).get("time_total_h")
        if totals is not None:
            verdict += (f" The paper's own measure, the total time of its 1000 tests (every one "
                        f"assembled): {totals[0]:.2f} h (baseline) vs {totals[1]:.2f} h (VGS); "
                        "ours counts every attempt until it was assembled or given up.")
        lines += ["", verdict, ""]
    lines += [f"![gains per training run]({figure})", ""]
    return "\n".join(lines)


def _run_arrays(df: pd.DataFrame, condition: str, policy: str
                ) -> tuple[np.ndarray, np.ndarray]:
    """``(times, successes)`` of ``policy`` on ``condition``, training runs x scenes (runs in
    name order, scenes by index)."""
    part = df[(df["condition"] == condition) & (df["policy"] == policy)]
    runs = sorted(set(part["train_run"])) if "train_run" in part.columns else [None]
    arrays = [time_arrays(part if run is None else part[part["train_run"] == run])
              for run in runs]
    return np.array([a[0] for a in arrays]), np.array([a[1] for a in arrays])


def field_table(df: pd.DataFrame, center: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per condition, the statistics Agarwal et al. (2021) recommend for few runs: the
    interquartile mean of the successes' assembly times per policy (pooled over runs and
    scenes) and the probability that VGS assembles faster than the baseline, and than the
    centre heuristic when given, on a random paired scene of a random run (a failed test is
    slower than any success; two failures tie, :func:`vgs.analysis.stats.win_matrix`), each
    with the crossed-bootstrap 95 % interval over runs and scenes
    (:func:`vgs.analysis.stats.crossed_interval`; the centre has no run: its scenes only)."""
    rows = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        tb, ob = _run_arrays(df, condition, "baseline")
        tv, ov = _run_arrays(df, condition, "vgs")
        if tb.shape != tv.shape or not tb.size:
            continue
        row: dict[str, Any] = {"condition": condition, "runs": tb.shape[0],
                               "scenes": tb.shape[1]}
        arrays = {"baseline": (tb, ob), "vgs": (tv, ov)}
        centre = center_of(df, condition, center)
        if centre is not None and len(centre) == tb.shape[1]:
            arrays["center"] = tuple(a[None, :] for a in time_arrays(centre))
        for policy, (t, ok) in arrays.items():
            value, low, high = iqm_interval(t, ok)
            row.update({f"iqm_s_{policy}": value, f"iqm_s_{policy}_ci_low": low,
                        f"iqm_s_{policy}_ci_high": high})
        for other in ("baseline", "center"):
            if other not in arrays:
                continue
            to, oo = arrays[other]
            wins = np.array([win_matrix(tv[r], ov[r], to[min(r, len(to) - 1)],
                                        oo[min(r, len(oo) - 1)]) for r in range(len(tv))])
            value, low, high = improvement_probability(wins)
            row.update({f"p_faster_than_{other}": value, f"p_faster_than_{other}_ci_low": low,
                        f"p_faster_than_{other}_ci_high": high})
        rows.append(row)
    return pd.DataFrame(rows)


def field_rows(field: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    """The header and rows of :func:`field_table` as text."""
    def cell(row: pd.Series, key: str, digits: int) -> str:
        value = row.get(key, math.nan)
        if not isinstance(value, float) or not math.isfinite(value):
            return "n/a"
        low, high = row[f"{key}_ci_low"], row[f"{key}_ci_high"]
        return f"{value:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"

    header = ["condition", "runs x scenes", "IQM of times [s], baseline", "VGS", "centre",
              "P(VGS faster than the baseline)", "P(VGS faster than the centre)"]
    rows = [[str(r["condition"]), f"{r['runs']} x {r['scenes']}",
             cell(r, "iqm_s_baseline", 1), cell(r, "iqm_s_vgs", 1), cell(r, "iqm_s_center", 1),
             cell(r, "p_faster_than_baseline", 3), cell(r, "p_faster_than_center", 3)]
            for _, r in field.iterrows()]
    return header, rows


def plot_profile(df: pd.DataFrame, path: Path, center: pd.DataFrame | None = None) -> Path:
    """Performance profiles: per condition, the fraction of tests assembled within ``t``
    seconds against ``t``, per policy (its runs pooled; thin lines: each run), the centre
    heuristic included when given. A curve that lies higher and further left is better; its
    right end is the policy's success rate."""
    conditions = [c for c in CONDITIONS if c in set(df["condition"])]
    fig, axes = plt.subplots(1, len(conditions), figsize=(4.4 * len(conditions), 3.6),
                             sharey=True, squeeze=False)
    for ax, condition in zip(axes[0], conditions, strict=True):
        curves = {p: _run_arrays(df, condition, p) for p in LEARNED}
        centre = center_of(df, condition, center)
        if centre is not None:
            curves["center"] = tuple(a[None, :] for a in time_arrays(centre))
        finite = np.concatenate([np.where(ok, t, np.nan).ravel()
                                 for t, ok in curves.values()])
        grid = np.linspace(0.0, float(np.nanmax(finite)) if np.isfinite(finite).any() else 1.0,
                           400)
        for policy, (t, ok) in curves.items():
            done = np.where(ok, t, np.inf)
            fraction = (done[..., None] <= grid).mean(axis=1)  # runs x grid
            if fraction.shape[0] > 1:
                for f in fraction:
                    ax.plot(grid, f, color=policy_color(policy), lw=0.6, alpha=0.35)
            ax.plot(grid, fraction.mean(axis=0), color=policy_color(policy), lw=1.8,
                    label=f"{policy} ({fraction.shape[0]} run{'s' if len(fraction) > 1 else ''})")
        ax.set_title(CONDITION_TITLES.get(condition, condition), fontsize=9)
        ax.set_xlabel("t [s, simulated]")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("fraction of tests assembled within t")
    axes[0][0].legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def seeds_report(folders: list[Path], dest: Path, center: Path | None = None) -> Path:
    """Write ``dest/seeds.md``, ``seeds.csv``, ``field.csv``, ``seeds.png`` and
    ``profile.png``; return the Markdown's path. ``center``: a results folder with the centre
    heuristic's tests on the same scenes (:func:`vgs.analysis.makeup.load_center`).

    Raises:
        ConfigError: On the folders (:func:`load_seeds`) or the centre's folder.
    """
    df = load_seeds(folders)
    centre = load_center(center, df) if center is not None else None
    table = seeds_table(df)
    field = field_table(df, centre)
    dest.mkdir(parents=True, exist_ok=True)
    rounded(table).to_csv(dest / "seeds.csv", index=False)  # times to the ms
    field.to_csv(dest / "field.csv", index=False, float_format="%.4f")
    plot_seeds(table, dest / "seeds.png")
    plot_profile(df, dest / "profile.png", centre)
    command = ("vgs seeds " + " ".join(str(f) for f in folders) + f" --out {dest}"
               + (f" --center {center}" if center is not None else ""))
    doc = Doc(dest)
    doc.h(2, "Across runs, the field's statistics")
    doc.p(f"Made by `{command}`. Interquartile mean (IQM) of the successes' assembly times, "
          "pooled over runs and scenes; P(VGS faster): the chance that on a random test scene "
          "of a random training run VGS assembled faster (a failed test is slower than any "
          "success, two failures tie: 1/2); 95 % intervals from the crossed bootstrap over "
          "runs and scenes (NumPy; `field.csv`).")
    doc.table(*field_rows(field))
    doc.img(dest / "profile.png", "Performance profile: the fraction of tests assembled "
                                  "within t seconds, per policy (thin lines: each run)")
    parts = makeups(df, centre)
    write_makeup(doc, parts, command)
    write_regret(doc, parts, command)
    path = dest / "seeds.md"
    path.write_text(seeds_markdown(table, folders, dest, "seeds.png", center) + "\n"
                    + doc.markdown())
    return path
