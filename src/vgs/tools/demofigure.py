"""The figure of one demo episode (matplotlib, headless): the heightmaps with the grasp, the F/T
signal with the phases, and the peg tip's path round the hole."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from vgs.assembly.record import PHASES  # noqa: E402
from vgs.sim.camera import Heightmap  # noqa: E402
from vgs.sim.rg2 import PAD_HALF  # noqa: E402
from vgs.tools.demo import DemoResult  # noqa: E402

PHASE_COLORS = {
    "idle": "#eeeeee", "grasp": "#d9d9d9", "transport": "#c6dbef", "approach": "#fdd0a2",
    "search": "#c7e9c0", "slide": "#fcbba1", "align": "#dadaeb", "insert": "#fff2ae",
    "release": "#f0f0f0",
}


def _segments(labels: Sequence[str]) -> list[tuple[int, int, str]]:
    """Runs of equal labels as ``(start, stop, label)`` index ranges."""
    runs, start = [], 0
    for i in range(1, len(labels) + 1):
        if i == len(labels) or labels[i] != labels[start]:
            runs.append((start, i, labels[start]))
            start = i
    return runs


def _shade_phases(ax: Axes, time: np.ndarray, phases: Sequence[str], legend: bool) -> None:
    seen = set()
    for start, stop, phase in _segments(phases):
        t1 = time[stop] if stop < len(time) else time[-1]
        label = phase if legend and phase not in seen else None
        ax.axvspan(time[start], t1, color=PHASE_COLORS.get(phase, "#ffffff"), alpha=0.8,
                   lw=0, label=label)
        seen.add(phase)


def _extent_mm(hm: Heightmap) -> list[float]:
    h, w = hm.depth.shape
    x0, y0 = hm.origin
    s = hm.pixel_size
    return [1000 * x0, 1000 * (x0 + w * s), 1000 * y0, 1000 * (y0 + h * s)]


def _draw_grasp(ax: Axes, result: DemoResult) -> None:
    """The pads (22 mm long, along the grasp heading) either side of the grasp point."""
    c = result.command
    along = np.array([math.cos(c.yaw), math.sin(c.yaw)])
    across = np.array([-along[1], along[0]])
    centre = np.array([c.x, c.y])
    half_gap = result.peg_radius + 0.003
    for side in (-1.0, 1.0):
        mid = centre + side * half_gap * across
        ends = np.array([mid - PAD_HALF[0] * along, mid + PAD_HALF[0] * along]) * 1000
        ax.plot(ends[:, 0], ends[:, 1], color="yellow", lw=3, solid_capstyle="butt")
    ax.plot(1000 * c.x, 1000 * c.y, "+", color="yellow", ms=10, mew=2)


def demo_figure(result: DemoResult, path: str | Path) -> Path:
    """Heightmaps with the grasp, the F/T signal with the phases, and the peg tip's path.

    Args:
        result: A traced demo episode.
        path: Output image file.

    Returns:
        The written path.
    """
    tr = result.trace
    time = np.asarray(tr.time)
    wrench = np.asarray(tr.wrench)
    phases = list(tr.phase)
    fig = plt.figure(figsize=(15, 10), layout="constrained")
    grid = fig.add_gridspec(3, 3, height_ratios=[1.3, 1, 1])
    hm = result.heightmap
    ext = _extent_mm(hm)
    window = _window_mm(result)
    ax = fig.add_subplot(grid[0, 0])
    ax.imshow(hm.color, origin="lower", extent=ext)
    _draw_grasp(ax, result)
    ax.set(title="(a) colour heightmap (crop) and grasp", xlabel="x [mm]", ylabel="y [mm]",
           xlim=window[0], ylim=window[1])
    ax = fig.add_subplot(grid[0, 1])
    if result.q_map is not None:  # a trained policy: its Q map on the peg pixels
        ax.imshow(hm.color, origin="lower", extent=ext)
        im = ax.imshow(np.ma.masked_where(hm.depth <= 0.005, result.q_map), origin="lower",
                       extent=ext, cmap="inferno", alpha=0.85)
        fig.colorbar(im, ax=ax, label="Q", shrink=0.8)
        title = f"(b) Q map of {result.policy} (crop) and its grasp"
    else:
        im = ax.imshow(1000 * hm.depth, origin="lower", extent=ext, cmap="viridis")
        fig.colorbar(im, ax=ax, label="height [mm]", shrink=0.8)
        title = "(b) depth heightmap (crop) and grasp"
    _draw_grasp(ax, result)
    ax.set(title=title, xlabel="x [mm]", xlim=window[0], ylim=window[1])
    _tip_path(fig.add_subplot(grid[0, 2]), result)
    ax_f = fig.add_subplot(grid[1, :])
    _shade_phases(ax_f, time, phases, legend=True)
    lines = [ax_f.plot(time, wrench[:, k], lw=0.8, label=f"F{n}")[0] for k, n in enumerate("xyz")]
    ax_f.set(ylabel="force at TCP [N]", title="(d) tared F/T signal (world frame) and phases")
    shades = ax_f.get_legend_handles_labels()[0][:-3]
    ax_f.legend(lines, [ln.get_label() for ln in lines], fontsize=8, loc="upper left",
                bbox_to_anchor=(1.0, 1.0))
    ax_t = fig.add_subplot(grid[2, :], sharex=ax_f)
    _shade_phases(ax_t, time, phases, legend=False)
    for k, name in enumerate("xyz"):
        ax_t.plot(time, wrench[:, 3 + k], lw=0.8, label=f"M{name}")
    ax_t.set(xlabel="simulated time [s]", ylabel="torque at TCP [N m]",
             title="(e) tared torque (world frame) and phases")
    handles, labels = ax_t.get_legend_handles_labels()
    ax_t.legend(handles + shades, labels + [h.get_label() for h in shades], fontsize=8,
                loc="upper left", bbox_to_anchor=(1.0, 1.0))
    rec = result.record
    status = "success" if rec.success else f"failed ({rec.failure_reason})"
    fig.suptitle(f"vgs demo, {result.policy}, seed {rec.seed}: {status}, assembly time "
                 f"{rec.assembly_time:.1f} s, {rec.adjustments} adjustments, grasp offset "
                 f"{1000 * rec.grasp_offset:+.1f} mm")
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _window_mm(result: DemoResult, half: float = 0.08) -> tuple[tuple[float, float], ...]:
    """x and y limits [mm] of a square of side ``2 half`` around the grasp point."""
    c = result.command
    return tuple((1000 * (v - half), 1000 * (v + half)) for v in (c.x, c.y))


def lowest_rim_points(tip: np.ndarray, tcp: np.ndarray, radius: float) -> np.ndarray:
    """Lowest point of the peg's lower face rim, per tick.

    The peg axis is taken along ``tip - tcp`` (the pads hold the peg on its axis), and the
    lowest rim point lies ``radius`` from the face centre along the downward direction
    projected onto the face.
    """
    axis = tip - tcp
    axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-12)
    down = np.array([0.0, 0.0, -1.0])
    v = down - (axis @ down)[:, None] * axis
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    return tip + np.where(norm > 1e-9, radius * v / np.maximum(norm, 1e-12), 0.0)


def _tip_path(ax: Axes, result: DemoResult) -> None:
    """The peg's lower end seen from above from the approach on, coloured by phase."""
    tr = result.trace
    tip = np.asarray(tr.peg_tip)
    rim = lowest_rim_points(tip, np.asarray(tr.tcp), result.peg_radius)  # search only
    phases = list(tr.phase)
    for k, phase in enumerate(p for p in PHASES if p != "transport"):
        idx = np.array([i for i, p in enumerate(phases) if p == phase], dtype=int)
        if idx.size:
            ax.plot(1000 * tip[idx, 0], 1000 * tip[idx, 1], lw=0.9, color=f"C{k}",
                    label=f"{phase}: face centre")
            if phase == "search":
                ax.plot(1000 * rim[idx, 0], 1000 * rim[idx, 1], lw=0.6, ls=":",
                        color="0.4", label="search: lowest rim point")
    hole = 1000 * result.hole_xy
    ax.add_patch(Circle((float(hole[0]), float(hole[1])), 1000 * result.hole_radius, fill=False,
                        color="k", lw=1.5, label="true hole"))
    ax.plot(*(1000 * result.nominal_hole_xy), "kx", label="nominal hole")
    ax.set_aspect("equal")
    span = 1000 * (result.hole_radius + 0.015)
    ax.set(xlim=(hole[0] - span, hole[0] + span), ylim=(hole[1] - span, hole[1] + span),
           title="(c) peg's lower end seen from above", xlabel="x [mm]", ylabel="y [mm]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
