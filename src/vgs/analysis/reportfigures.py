"""What the reproduction report shows and in which order (the learned modes, the conditions' titles,
the policies' order and colours) and its figures of the test episodes."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from vgs.analysis.palette import policy_color  # noqa: E402
from vgs.analysis.stats import com_shifted  # noqa: E402
from vgs.config import CONDITIONS  # noqa: E402

LEARNED = ("baseline", "vgs")


CONDITION_TITLES = {
    "nominal": "Nominal peg (paper Fig. 8)",
    "mass": "Mass +-15 % (paper Fig. 9)",
    "length": "Length 85-115 %, mass following (paper Fig. 10)",
    "com": "Centre of mass 20 mm off the middle, heavy end painted",
    "com-hidden": "Centre of mass 20 mm off the middle, unmarked",
    "com-spread": "Centre of mass spread within +-20 mm, unmarked",
}


def policy_order(policies: list[str]) -> list[str]:
    """Learned policies first (baseline, vgs), then the references."""
    return [p for p in LEARNED if p in policies] + sorted(p for p in policies if p not in LEARNED)


def _color(policy: str) -> str:
    return policy_color(policy)


def plot_times(df: pd.DataFrame, condition: str, path: Path) -> Path:
    """Assembly time of every successful test episode (left) and their distribution (right)."""
    part = df[(df["condition"] == condition) & df["assembly_success"].astype(bool)]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    times_all = part["assembly_time_s"].to_numpy(float)
    bins = (np.linspace(times_all.min(), times_all.max(), 30) if times_all.size > 1 else 10)
    for policy in policy_order(sorted(set(df["policy"]))):
        mine = part[part["policy"] == policy]
        if mine.empty:
            continue
        t = mine["assembly_time_s"].to_numpy(float)
        ax1.plot(mine["index"], t, ".", ms=4, alpha=0.7, color=_color(policy),
                 label=f"{policy} (mean {t.mean():.1f} s, n={t.size})")
        ax1.axhline(t.mean(), color=_color(policy), lw=1)
        ax2.hist(t, bins=bins, alpha=0.45, color=_color(policy), label=policy)
    ax1.set_xlabel("test episode")
    ax1.set_ylabel("assembly time [s, simulated]")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("assembly time [s, simulated]")
    ax2.set_ylabel("episodes")
    ax2.legend(fontsize=8)
    fig.suptitle(f"Assembly time, successful tests: {CONDITION_TITLES[condition]}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_grasp_positions(df: pd.DataFrame, path: Path) -> Path:
    """Where each policy grasped: the realised offset along the peg from its middle (top row;
    the centre of mass of a uniform peg) and, on a condition whose centre of mass is off the
    middle, from the centre of mass (bottom row). Positive offsets point to the heavy end
    (body +z); ground truth (``grasp_offset_mm``, ``grasp_offset_com_mm``)."""
    conditions = [c for c in CONDITIONS if c in set(df["condition"])]
    shifted = {c for c in conditions if com_shifted(df[df["condition"] == c])}
    rows = [("grasp_offset_mm", "from the middle")]
    if shifted:
        rows.append(("grasp_offset_com_mm", "from the centre of mass"))
    fig, axes = plt.subplots(len(rows), len(conditions),
                             figsize=(4.5 * len(conditions), 3.6 * len(rows)), squeeze=False)
    bins = np.linspace(-60, 60, 41)
    for r, (column, reference) in enumerate(rows):
        for ax, condition in zip(axes[r], conditions, strict=True):
            if column == "grasp_offset_com_mm" and condition not in shifted:
                ax.axis("off")
                continue
            part = df[(df["condition"] == condition) & df["grasp_success"].astype(bool)]
            for policy in policy_order(sorted(set(df["policy"]))):
                off = part.loc[part["policy"] == policy, column].dropna()
                if off.empty:
                    continue
                ax.hist(off, bins=bins, alpha=0.45, color=_color(policy),
                        label=f"{policy} (mean |l| {off.abs().mean():.1f} mm)")
            ax.axvline(0.0, color="0.3", lw=0.8)
            ax.set_title(condition)
            ax.set_xlabel(f"grasp offset {reference} [mm], + heavy end"
                          if condition in shifted else f"grasp offset {reference} [mm]")
            ax.set_ylabel("grasps")
            ax.legend(fontsize=7)
    fig.suptitle("Where each policy grasps along the peg (test episodes, ground truth)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
