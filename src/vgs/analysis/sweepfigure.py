"""The figure of the grasp-offset sweep (matplotlib, headless) and the disturbing moments of
paper eq. 2 and 3 that it draws beside the assembly times."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402

from vgs.analysis.palette import policy_color  # noqa: E402
from vgs.analysis.stats import population_std  # noqa: E402
from vgs.config import ExperimentConfig  # noqa: E402
from vgs.control.arm import GRAVITY  # noqa: E402


def sweep_figure(rows: Sequence[dict[str, Any]], summary: Sequence[dict[str, Any]],
                 cfg: ExperimentConfig, path: str | Path, title: str = "") -> Path:
    """Assembly time and success against the grasp offset, with M_G and M_I (eq. 2, 3).

    Args:
        rows: Sweep rows (see :data:`vgs.experiments.sweep.COLUMNS`).
        summary: Their per-offset summary (:func:`vgs.analysis.sweepstats.summarize`).
        cfg: The sweep's configuration (nominal peg mass, search tilt, wiggle).
        path: Output image file.
        title: Figure title.

    Returns:
        The written path.
    """
    offsets = np.array([s["offset_mm"] for s in summary])
    fig, (ax, ax_a, ax_s) = plt.subplots(3, 1, figsize=(8, 10), sharex=True,
                                         height_ratios=[2, 1.2, 1], layout="constrained")
    ok = [r for r in rows if r["assembly_success"]]
    rng = np.random.default_rng(0)  # jitter of the faint points only
    spacing = np.min(np.diff(offsets)) if offsets.size > 1 else 10.0
    jitter = rng.uniform(-0.12, 0.12, len(ok)) * spacing
    x_ok = np.array([r["offset_mm"] for r in ok]) + jitter
    ax.scatter(x_ok, [r["assembly_time_s"] for r in ok], s=8, color=policy_color("center"),
               alpha=0.25, lw=0, label="successful trials")
    _mean_std(ax, summary, "time", policy_color("center"), "mean +- std")
    ax.set(ylabel="assembly time [s] (simulated)")
    ax.set_title(title or "Assembly time against grasp offset")
    _moment_axis(ax, cfg, offsets)
    align = [_phase_stats([r for r in ok if r["offset_mm"] == o], ("align",))
             for o in offsets]
    ax_a.scatter(x_ok, [r["time_align_s"] for r in ok], s=8, color="C2", alpha=0.25, lw=0)
    ax_a.errorbar(offsets, [a[0] for a in align], yerr=[a[1] for a in align], color="C2",
                  marker="o", capsize=3, label="alignment, mean +- std")
    ax_a.set(ylabel="alignment time [s]")
    ax_a.legend(fontsize=8)
    ax_s.bar(offsets, [100 * s["success_rate"] for s in summary], width=0.6 * spacing,
             color="C7")
    for o, s in zip(offsets, summary, strict=True):
        ax_s.annotate(f"{s['successes']}/{s['n']}", (o, 100 * s["success_rate"]),
                      ha="center", va="bottom", fontsize=7)
    ax_s.set(ylabel="success [%]", ylim=(0, 112),
             xlabel="grasp offset from the visible peg centre along its axis [mm]")
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _phase_stats(group: Sequence[dict[str, Any]], phases: Sequence[str]) -> tuple[float, float]:
    if not group:
        return math.nan, math.nan
    values = np.array([sum(r[f"time_{p}_s"] for p in phases) for r in group])
    return float(values.mean()), population_std(values)


def _mean_std(ax: Axes, summary: Sequence[dict[str, Any]], key: str, color: str,
              label: str) -> None:
    x = np.array([s["offset_mm"] for s in summary])
    mean = np.array([np.nan if s[f"{key}_mean_s"] is None else s[f"{key}_mean_s"]
                     for s in summary])
    std = np.array([np.nan if s[f"{key}_std_s"] is None else s[f"{key}_std_s"]
                    for s in summary])
    ax.errorbar(x, mean, yerr=std, color=color, marker="o", capsize=3, label=label)


def moment_unit(values: np.ndarray) -> tuple[float, str]:
    """``(factor, unit)`` that shows moments in N m ``values`` with a maximum of 1 to 1000:
    N m, mN m, uN m or nN m."""
    peak = float(np.max(np.abs(values))) if np.size(values) else 0.0
    for factor, unit in ((1.0, "N m"), (1e3, "mN m"), (1e6, "uN m")):
        if peak * factor >= 1.0:
            return factor, unit
    return 1e9, "nN m"


def _moment_axis(ax: Axes, cfg: ExperimentConfig, offsets: np.ndarray) -> None:
    """M_G and M_I of the nominal peg, each on its own y axis in the unit that fits it (M_I is
    about a thousandth of M_G: on one axis it would be a flat line)."""
    lever = np.linspace(offsets.min(), offsets.max(), 200) / 1000.0
    if np.ptp(lever) == 0:
        lever = np.linspace(-0.035, 0.035, 200)
    m_g, m_i = disturbing_moments(cfg, lever)
    a = cfg.assembly
    twin = ax.twinx()
    f_g, u_g = moment_unit(m_g)
    twin.plot(1000 * lever, f_g * m_g, "C3-", lw=1.2,
              label=f"M_G [{u_g}] = m g |l| sin(beta), beta = {a.search_tilt_deg:g} deg "
                    "(search tilt)")
    twin.set_ylabel(f"M_G [{u_g}] (solid), m = {cfg.cell.peg.mass:g} kg")
    twin.set_ylim(bottom=0)
    third = ax.twinx()
    third.spines.right.set_position(("axes", 1.14))
    f_i, u_i = moment_unit(m_i)
    third.plot(1000 * lever, f_i * m_i, "C1--", lw=1.2,
               label=f"M_I [{u_i}] = (1/2) m l^2 (2 pi / T)^2 A, sinusoidal wiggle "
                     f"A = {a.wiggle_amplitude_deg:g} deg, T = {a.wiggle_period:g} s")
    third.set_ylabel(f"M_I [{u_i}] (outer right axis, dashed)")
    third.set_ylim(bottom=0)
    lines = ax.get_legend_handles_labels()
    handles, labels = lines
    for axis in (twin, third):
        h, lab = axis.get_legend_handles_labels()
        handles, labels = handles + h, labels + lab
    ax.legend(handles, labels, fontsize=7, loc="upper center")


def disturbing_moments(cfg: ExperimentConfig, lever: np.ndarray,
                       mass: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Paper eq. 2 and 3 for the grasp lever arms ``lever`` [m].

    ``M_G = m g |l| sin(beta)`` with beta the search tilt ``assembly.search_tilt_deg`` (the
    angle between gravity and the peg axis that the controller holds), and
    ``M_I = (1/2) m r^2 d2beta/dt2`` with ``r = |l|`` and the peak angular acceleration of a
    sinusoidal wiggle of amplitude A and period T: ``(2 pi / T)^2 A``.

    Args:
        cfg: Experiment configuration (assembly settings, nominal peg mass).
        lever: Distances from the pads to the centre of mass [m].
        mass: Peg mass [kg]; default the configured one.

    Returns:
        ``(M_G, M_I)`` in N m.
    """
    m = cfg.cell.peg.mass if mass is None else mass
    a = cfg.assembly
    lever = np.abs(np.asarray(lever, dtype=float))
    m_g = m * GRAVITY * lever * math.sin(math.radians(a.search_tilt_deg))
    accel = (2.0 * math.pi / a.wiggle_period) ** 2 * math.radians(a.wiggle_amplitude_deg)
    m_i = 0.5 * m * lever**2 * accel
    return m_g, m_i
