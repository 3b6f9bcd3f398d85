"""Which input does the position action learn from better: the heightmap turned into the jaws'
frame, or as captured? (issue 39, item 1: decided by measurement.)

Fresh networks, one per ``network.rotate`` mode of the position action (``input``: each
heightmap turned once by its perceived jaw angle before the trunks; ``none``: as captured), are
fitted to the same transitions of a training run (``episodes.csv``: scene seed, executed pixel,
reward; the heightmaps re-rendered from the scene seeds as the replay does), in the same random
order, with the agent's own SGD step (:meth:`GraspAgent.update`, target y = R). Each network
then grasps greedily (masked to the peg) on held-out scenes; the script prints where along the
peg those grasps lie (ground truth, analysis only: the chosen pixel's world point projected on
the peg's true axis, from its centre of mass) and how tightly they concentrate (interquartile
range and the share within 5 mm of their median). The mode whose greedy grasps concentrate
better is the profiles' default.

Run: ``.venv/bin/python scripts/fit_input_modes.py runs/paper_light_s0/train/vgs_s0
--transitions 1000 --steps 3000 --test-seeds 100`` (what docs/training.md reports)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch
from tqdm import tqdm

from vgs.assembly.episode import EpisodeRunner
from vgs.config import override, profile
from vgs.grasping.actions import peg_mask
from vgs.grasping.agent import GraspAgent
from vgs.grasping.transition import Transition


def offset_mm(runner: EpisodeRunner, seed: int, row: int, col: int) -> float:
    """Signed distance [mm] along the peg's true axis from its centre to pixel (row, col)."""
    cell, cam = runner.cell(runner.cfg.cell.peg)
    cell.reset(np.random.default_rng(seed))
    p_world_peg, R_world_peg = cell.peg_pose()
    hm = cam.capture(cell.data)
    x, y = hm.pixel_to_world(row, col)
    axis = R_world_peg[:2, 2] / np.linalg.norm(R_world_peg[:2, 2])
    return float(np.dot(np.array([x, y]) - p_world_peg[:2], axis) * 1000.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="a training run folder (episodes.csv)")
    parser.add_argument("--profile", default="paper-light")
    parser.add_argument("--rotate", nargs="+", default=["input", "none"])
    parser.add_argument("--transitions", type=int, default=1000,
                        help="the run's first N episodes are the data")
    parser.add_argument("--steps", type=int, default=3000, help="SGD steps per network")
    parser.add_argument("--test-seeds", type=int, default=100)
    parser.add_argument("--net-seed", type=int, default=0)
    args = parser.parse_args()
    cfg = override(profile(args.profile), "network.action", "position")
    runner = EpisodeRunner(cfg)
    table = pd.read_csv(args.run / "episodes.csv").head(args.transitions)
    seeds = [int(s) for s in table.seed]
    test_seeds = [10_000_000 + i for i in range(args.test_seeds)]
    maps = {}
    for s in tqdm(seeds + test_seeds, desc="render", mininterval=10):
        hm = runner.observe(s)
        maps[s] = (hm.color, hm.depth)
    print(f"{args.run}: {len(table)} transitions, mean reward {table.reward.mean():.3f}, "
          f"{(table.reward > cfg.reward.grasp + 1e-9).mean():.0%} with the assembly reward")
    order = np.random.default_rng(args.net_seed).integers(len(table), size=args.steps)
    for mode in args.rotate:
        network_cfg = override(cfg, "network.rotate", mode).network
        agent = GraspAgent(network_cfg, cfg.agent, seed=args.net_seed)
        t0 = time.perf_counter()
        for n in tqdm(order, desc=f"fit rotate={mode}", mininterval=10):
            row = table.iloc[int(n)]
            color, depth = maps[int(row.seed)]
            agent.update(Transition(color, depth, (0, int(row.row), int(row.col)),
                                    float(row.reward), done=True))
        rng = np.random.default_rng(0)
        offsets = []
        for s in test_seeds:
            color, depth = maps[s]
            action = agent.act(color, depth, 0.0, peg_mask(depth), rng)
            offsets.append(offset_mm(runner, s, action.row, action.col))
        o = np.asarray(offsets)
        q1, med, q3 = np.percentile(o, [25, 50, 75])
        near = float(np.mean(np.abs(o - med) <= 5.0))
        print(f"rotate={mode:<5} {args.steps} steps ({time.perf_counter() - t0:.0f} s): greedy "
              f"grasp offsets median {med:+.1f} mm, |offset| median "
              f"{np.median(np.abs(o)):.1f} mm, interquartile range {q3 - q1:.1f} mm, "
              f"{near:.0%} within 5 mm of the median", flush=True)


if __name__ == "__main__":
    torch.set_num_threads(1)
    main()
