"""Learning curves of training runs and where each policy grasps along the peg.

Reads ``episodes.csv`` of one or more runs (``vgs train``) and draws, against the episode:
the moving grasp success rate, the moving assembly time of successful assemblies and the
moving reward; and the distribution of |grasp offset| (ground truth, analysis only) in the
random-exploration phase beside the last ``window`` episodes. Also returns a summary per run.

What a training did not measure is marked, not drawn as a measurement: a run whose grasps ran
without the assembly (``train.assemble_baseline = False``: ``no_assembly`` rows) has no time
curve and no legend entry there, its assembly numbers are "skipped" (NaN in the summary, with
``assembly_skipped``); assemblies stopped at the frozen reward threshold
(``train.stop_at_threshold``: ``cutoff:<phase>`` rows) leave only the times below the
threshold, so the time panel draws the threshold and says from which episode the stops began.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from vgs.analysis.palette import LINESTYLES, policy_color  # noqa: E402
from vgs.errors import ConfigError  # noqa: E402


def load_episodes(run_dir: Path) -> tuple[pd.DataFrame, dict]:
    """The episode table (column vocabulary of :mod:`vgs.columns`, booleans as booleans also
    for tables written with 0/1) and run metadata of a run.

    Raises:
        ConfigError: If the folder holds no episodes.
    """
    table, meta = run_dir / "episodes.csv", run_dir / "run.json"
    if not table.exists() or not meta.exists():
        raise ConfigError("run_dir", f"{run_dir} holds no training run (episodes.csv, run.json)")
    from vgs.runfolder.common import read_json, read_table

    return read_table(table, "train"), read_json(meta)


def skipped(df: pd.DataFrame) -> pd.Series:
    """Rows whose grasp ran without the assembly (``train.assemble_baseline = False``)."""
    return df.failure_reason.astype(object).fillna("").astype(str).eq("no_assembly")


def stopped(df: pd.DataFrame) -> pd.Series:
    """Rows whose assembly stopped at the frozen reward threshold (``train.stop_at_threshold``)."""
    return df.failure_reason.astype(object).fillna("").astype(str).str.startswith("cutoff:")


def summarize(df: pd.DataFrame, random_episodes: int, window: int) -> dict[str, float]:
    """Grasp success, assembly success and time, |offset| in the random phase and at the end."""
    def stats(part: pd.DataFrame) -> dict[str, float]:
        ok = part[part.assembly_success]
        held = part[part.grasp_success]
        assembled = part[~skipped(part)]  # the episodes that ran an assembly
        return {
            "episodes": int(len(part)),
            "grasp_success": float(part.grasp_success.mean()) if len(part) else float("nan"),
            "assembly_skipped": bool(len(part)) and not len(assembled),
            "threshold_stops": int(stopped(part).sum()),
            "assembly_success": float(assembled.assembly_success.mean()) if len(assembled)
            else float("nan"),
            "assembly_time_mean_s": float(ok.assembly_time_s.mean()) if len(ok) else float("nan"),
            "abs_offset_mean_mm": float(held.grasp_offset_mm.abs().mean()) if len(held)
            else float("nan"),
            "reward_mean": float(part.reward.mean()) if len(part) else float("nan"),
        }

    return {"random_phase": stats(df[df.episode < random_episodes]),
            "last_window": stats(df[df.episode >= df.episode.max() + 1 - window])}


def plot_curves(run_dirs: list[Path], out: Path, window: int = 20) -> dict[str, dict]:
    """Write the figure; return ``{run name: summary}``.

    Raises:
        ConfigError: On a window < 1 or a folder without a run.
    """
    if window < 1:
        raise ConfigError("window", f"must be >= 1, got {window}")
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    (ax_g, ax_t), (ax_r, ax_o) = axes
    summaries: dict[str, dict] = {}
    offsets = []
    notes: list[str] = []
    seen: dict[str, int] = {}
    for run in run_dirs:
        df, meta = load_episodes(run)
        mode = meta["mode"]
        # one colour per policy (vgs.analysis.palette); its runs told apart by line style
        style = {"color": policy_color(mode),
                 "ls": LINESTYLES[seen.setdefault(mode, 0) % len(LINESTYLES)]}
        seen[mode] += 1
        random_episodes = int(meta["config"]["agent"]["random_episodes"])
        label = f"{mode} ({run.name})"
        summaries[label] = summarize(df, random_episodes, window)
        roll = df.rolling(window, min_periods=max(1, window // 2))
        ax_g.plot(df.episode, roll.grasp_success.mean(), label=label, **style)
        if not skipped(df).all():
            times = df.assembly_time_s.where(df.assembly_success)
            ax_t.plot(df.episode, times.rolling(window, min_periods=min(3, window)).mean(),
                      label=label, **style)
        else:
            notes.append(f"{label}: assemblies skipped in training")
        cut = stopped(df)
        if cut.any() and "threshold_s" in df.columns:
            first = int(df.episode[cut].min())
            ax_t.plot(df.episode, df.threshold_s, color=style["color"], ls=":", lw=1.2,
                      label=f"{mode} ({run.name}) reward threshold")
            notes.append(f"{label}: {int(cut.sum())} assemblies stopped at the threshold "
                         f"(from episode {first}; times above it not measured)")
        ax_r.plot(df.episode, roll.reward.mean(), label=label, **style)
        held = df[df.grasp_success]
        offsets.append((label + ", random phase",
                        held[held.episode < random_episodes].grasp_offset_mm.abs(),
                        {**style, "alpha": 0.45}))
        offsets.append((label + f", last {window}",
                        held[held.episode >= df.episode.max() + 1 - window].grasp_offset_mm.abs(),
                        style))
        for ax in (ax_g, ax_t, ax_r):
            ax.axvline(random_episodes, color="grey", ls=":", lw=1)
    ax_g.set_ylabel(f"grasp success (moving mean, {window})")
    ax_t.set_ylabel(f"assembly time [s] (successful, moving mean {window})")
    ax_r.set_ylabel(f"reward (moving mean, {window})")
    for ax in (ax_g, ax_t, ax_r):
        ax.set_xlabel("episode (dotted: end of random exploration)")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7 if ax is ax_t else 8)
    if notes:
        ax_t.set_title("\n".join(textwrap.fill(n, 80) for n in notes), fontsize=7,
                       color="0.3")
    bins = np.linspace(0, 50, 11)
    for label, values, style in offsets:
        if len(values):
            ax_o.hist(values, bins=bins, histtype="step", lw=1.5, density=True,
                      label=f"{label} (n={len(values)})", **style)
    ax_o.set_xlabel("|grasp offset from the centre of mass| [mm] (ground truth)")
    ax_o.set_ylabel("density")
    ax_o.legend(fontsize=7)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return summaries
