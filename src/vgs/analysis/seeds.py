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

from vgs.analysis.palette import GAIN_COLORS  # noqa: E402
from vgs.analysis.report import PAPER, load_results  # noqa: E402
from vgs.analysis.reportfigures import CONDITION_TITLES, LEARNED  # noqa: E402
from vgs.analysis.stats import (  # noqa: E402
    ALIGN_GAIN,
    BOOTSTRAP_RESAMPLES,
    GAINS,
    MEAN_GAIN,
    SUCCESS_TOTAL_GAIN,
    TOTAL_GAIN,
    Measure,
    efficiency_gain,
    sample_std,
    summarize,
    t_interval,
    time_arrays,
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


def mean_gain(pairs: list[tuple[pd.DataFrame, pd.DataFrame]],
              resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0,
              measure: Measure = MEAN_GAIN) -> tuple[float, float, float]:
    """Mean over training runs of the gain, with the crossed bootstrap's 95 % interval (runs
    and one shared draw of test scenes per replicate; module docstring).

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
    rng = np.random.default_rng(seed)
    out = np.empty(resamples)
    n = len(arrays[0][0])
    for b in range(resamples):
        runs = rng.integers(len(arrays), size=len(arrays))
        i = rng.integers(n, size=n)  # one draw of the shared scenes for every drawn run
        total = 0.0
        for s in runs:
            tb, ob, tv, ov = arrays[s]
            total += measure(tb[i], ob[i], tv[i], ov[i])
        out[b] = total / len(arrays)
    out = out[np.isfinite(out)]
    if not out.size:
        return value, math.nan, math.nan
    low, high = np.percentile(out, [2.5, 97.5])
    return value, float(low), float(high)


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
    fig, axes = plt.subplots(1, len(conditions), figsize=(4.2 * len(conditions), 1.4 + 0.5 *
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
                ax.plot(row[f"{key}_pct"], yi,
                        "D" if mean else ("o" if key == MEAN_GAIN.name else "s"),
                        color=color, ms=7 if mean else 5)
        ax.axvline(0.0, color="gray", lw=0.8)
        paper = PAPER.get(condition, {}).get("gain")
        if paper is not None:
            ax.axvline(paper, color=GAIN_COLORS["paper"], ls="--", lw=1.2)
            ax.text(paper, len(runs) - 0.45, f" paper {paper:+.2f} %", color=GAIN_COLORS["paper"],
                    fontsize=8, va="center")
        ax.set_ylim(-0.6, len(runs) - 0.2)
        ax.set_title(CONDITION_TITLES.get(condition, condition), fontsize=9)
        ax.set_xlabel("efficiency gain of VGS [%] (95 % CI)")
    axes[0][0].plot([], [], "o", color=GAIN_COLORS["gain"], label="mean time of successes")
    axes[0][0].plot([], [], "s", color=GAIN_COLORS["total_gain"], label="total time of all tests")
    axes[0][0].legend(fontsize=7, loc="lower left")
    axes[0][0].set_yticks(list(y_of.values()), runs)
    axes[0][0].set_ylabel("training run")
    fig.tight_layout()
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


def _interval_verdict(low: float, high: float) -> str:
    if not math.isfinite(low):
        return "too few successes for an interval."
    if low > 0:
        return "its interval lies above zero."
    if high < 0:
        return "its interval lies below zero: VGS is slower here."
    return "its interval includes zero: no difference shown."


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


def seeds_markdown(table: pd.DataFrame, folders: list[Path], dest: Path, figure: str) -> str:
    """The tables of :func:`seeds_table` as Markdown."""
    lines = ["# VGS against the baseline, across training seeds", "",
             "Written by `vgs seeds " + " ".join(str(f) for f in folders) + f" --out {dest}` "
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
        verdict += "the mean gain: " + _interval_verdict(mean["gain_ci_low"],
                                                          mean["gain_ci_high"])
        verdict += (f" In total time, {int(mean['seeds_with_positive_total_gain'])} of {seeds} "
                    "training runs give VGS the shorter total; the mean gain in total time: "
                    + _interval_verdict(mean["total_gain_ci_low"], mean["total_gain_ci_high"]))
        verdict += (f" In the alignment phase, {int(mean['seeds_with_positive_align_gain'])} of "
                    f"{seeds} training runs give VGS the shorter mean; the mean gain: "
                    + _interval_verdict(mean["align_gain_ci_low"], mean["align_gain_ci_high"]))
        if paper is not None:
            verdict += f" The paper reports {paper:+.2f} %."
        totals = PAPER.get(condition, {}).get("time_total_h")
        if totals is not None:
            verdict += (f" The paper's own measure, the total time of its 1000 tests (every one "
                        f"assembled): {totals[0]:.2f} h (baseline) vs {totals[1]:.2f} h (VGS); "
                        "ours counts every attempt until it was assembled or given up.")
        lines += ["", verdict, ""]
    lines += [f"![gains per training run]({figure})", ""]
    return "\n".join(lines)


def seeds_report(folders: list[Path], dest: Path) -> Path:
    """Write ``dest/seeds.md``, ``seeds.csv`` and ``seeds.png``; return the Markdown's path."""
    table = seeds_table(load_seeds(folders))
    dest.mkdir(parents=True, exist_ok=True)
    rounded(table).to_csv(dest / "seeds.csv", index=False)  # times to the ms
    plot_seeds(table, dest / "seeds.png")
    path = dest / "seeds.md"
    path.write_text(seeds_markdown(table, folders, dest, "seeds.png"))
    return path
