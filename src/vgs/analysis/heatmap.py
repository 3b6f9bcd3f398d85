"""Q-value heat maps over the heightmap, untrained beside trained (paper Figure 7).

The untrained network is the run's network at its initial parameters (same seed, no updates);
the trained one is loaded from the run's checkpoint. Each panel shows the Q map of the position
action (``network.action = position``: one map, jaws across the perceived axis), or
``max_k Q(k, i, j)`` over the rotations of the rotation action, drawn over the colour heightmap,
and marks the greedy grasp on the peg. The two panels of a scene share one colour scale (the
range of both maps over the peg's pixels) and one colour bar.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vgs.assembly.episode import EpisodeRunner  # noqa: E402
from vgs.config import ExperimentConfig  # noqa: E402
from vgs.grasping.agent import GraspAgent  # noqa: E402
from vgs.grasping.preprocess import peg_mask  # noqa: E402
from vgs.rollout.policies import load_trained_agent  # noqa: E402
from vgs.runfolder.trainfolder import episode_seed  # noqa: E402

ZOOM = 0.08  # half-width of the window around the peg [m]


def load_run(run_dir: Path) -> tuple[ExperimentConfig, str, GraspAgent, GraspAgent]:
    """Config, mode, untrained agent and trained agent of a training run.

    Raises:
        ConfigError: If the folder holds no finished checkpoint.
    """
    cfg, meta, trained, _ = load_trained_agent(run_dir, field="run_dir")
    untrained = GraspAgent(cfg.network, cfg.agent, device="cpu", seed=cfg.seed)
    return cfg, meta["mode"], untrained, trained


def plot_heatmaps(run_dir: Path, out: Path, scenes: int = 2, seed: int = 12345) -> Path:
    """Write the figure: one row per scene, untrained and trained Q maps side by side."""
    cfg, mode, untrained, trained = load_run(run_dir)
    runner = EpisodeRunner(cfg)
    label = "Q" if cfg.network.action == "position" else "max over rotations of Q"
    fig, axes = plt.subplots(scenes, 2, figsize=(9, 4 * scenes), squeeze=False,
                             layout="constrained")
    for s in range(scenes):
        hm = runner.observe(episode_seed(seed, s))
        mask = peg_mask(hm.depth)
        extent = (hm.origin[0], hm.origin[0] + hm.depth.shape[1] * hm.pixel_size,
                  hm.origin[1], hm.origin[1] + hm.depth.shape[0] * hm.pixel_size)
        pair = [(agent.q_values(hm.color, hm.depth).max(axis=0), title)
                for agent, title in ((untrained, "untrained"), (trained, "trained"))]
        # One colour scale for the pair, over the peg's pixels of both maps: the two panels
        # compare by colour.
        on_peg = np.concatenate([q[mask] for q, _ in pair]) if mask.any() else \
            np.concatenate([q.ravel() for q, _ in pair])
        vmin, vmax = float(on_peg.min()), float(on_peg.max())
        for col, (q, title) in enumerate(pair):
            ax = axes[s, col]
            ax.imshow(hm.color, origin="lower", extent=extent)
            shown = np.ma.masked_where(~mask, q)
            im = ax.imshow(shown, origin="lower", extent=extent, cmap="jet", alpha=0.75,
                           vmin=vmin, vmax=vmax)
            masked = np.where(mask, q, -np.inf)
            i, j = np.unravel_index(int(np.argmax(masked)), q.shape)
            x, y = hm.pixel_to_world(i, j)
            ax.plot(x, y, "w+", ms=14, mew=2)
            rows, cols = np.nonzero(mask)
            if rows.size:  # zoom on the peg: 8 cm around it
                xs, ys = hm.pixel_to_world(rows, cols)
                cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
                ax.set_xlim(cx - ZOOM, cx + ZOOM)
                ax.set_ylim(cy - ZOOM, cy + ZOOM)
            ax.set_title(f"{title} ({mode})")
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
        fig.colorbar(im, ax=list(axes[s]), fraction=0.046, label=f"{label} (one scale for "
                                                                 "the pair)")
    fig.suptitle("Grasp Q values on the peg (cross: greedy grasp)")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
