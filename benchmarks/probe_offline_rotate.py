"""Can the network learn the jaw angle from a training run's own data? (issue 18: seed 0's
learned `paper-light` policies close their jaws a median 29-40 deg off the peg's axis.)
An offline analysis probe; figures only, nothing in vgs depends on it.

Fresh networks, one per ``--rotate`` mode (``input``: the heightmaps are turned R times before
the trunks, as in VPG and the paper; ``features``: one trunk pass and an angle-coded head, the
`paper-light` profile's mode until 2026-12-03), are fitted to the same logged transitions of a
finished training run (``episodes.csv``: scene seed, executed rotation and pixel, reward), in
the same random order, with the agent's own SGD step (:meth:`GraspAgent.update`, target
y = R). The heightmaps are re-rendered from the scene seeds as the replay does. Each network
then chooses greedily (masked to the peg, as in the tests) on held-out test scenes, and the
probe prints how far its jaws lie from the peg's true axis (ground truth, analysis only;
``probe_policy_jaw_angle.misalignment_deg``), beside the run's own final network.

Run: ``.venv/bin/python benchmarks/probe_offline_rotate.py runs/paper_light_features_s0/train/vgs_s0
--steps 5000 --test-seeds 200`` (what docs/training.md reports)
"""

from __future__ import annotations

import argparse
import itertools
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch
from tqdm import tqdm

from probe_policy_jaw_angle import misalignment_deg  # this folder (the script's) is on sys.path
from vgs.assembly.episode import EpisodeRunner
from vgs.config import override, profile
from vgs.experiments.policies import load_trained_agent
from vgs.grasping.agent import GraspAgent
from vgs.grasping.preprocess import peg_mask
from vgs.grasping.transition import Transition


def greedy_misalignments(agent: GraspAgent, runner: EpisodeRunner, maps: dict[int, tuple],
                         seeds: list[int]) -> np.ndarray:
    rng = np.random.default_rng(0)
    out = []
    for seed in seeds:
        color, depth = maps[seed]
        action = agent.act(color, depth, 0.0, peg_mask(depth), rng)
        out.append(misalignment_deg(runner, seed, action.rotation, agent.num_rotations))
    return np.asarray(out)


def summary(name: str, m: np.ndarray, rotations: int, seconds: float) -> str:
    within = float(np.mean(m <= 180.0 / rotations))
    return (f"{name:<28} median {np.median(m):5.1f} deg, mean {np.mean(m):5.1f} deg, "
            f"{within:4.0%} within {180 / rotations:.2f} deg  ({seconds:.0f} s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="a finished training run folder")
    parser.add_argument("--profile", default="paper-light")
    parser.add_argument("--rotate", nargs="+", default=["input", "features"])
    parser.add_argument("--transitions", type=int, default=5000,
                        help="the run's first N episodes are the data")
    parser.add_argument("--steps", type=int, default=6000, help="SGD steps per network")
    parser.add_argument("--test-seeds", type=int, default=100)
    parser.add_argument("--net-seed", type=int, default=0)
    parser.add_argument("--precision", nargs="+", default=["float32"],
                        help="network.precision of the fitted networks (float32, bfloat16)")
    parser.add_argument("--skip-own", action="store_true",
                        help="do not measure the run's own final network")
    args = parser.parse_args()
    torch.set_num_threads(2)
    cfg = profile(args.profile)
    rotations = cfg.network.num_rotations
    runner = EpisodeRunner(cfg)
    table = pd.read_csv(args.run / "episodes.csv").head(args.transitions)
    seeds = [int(s) for s in table.seed]
    test_seeds = [10_000_000 + i for i in range(args.test_seeds)]
    maps: dict[int, tuple] = {}
    for s in tqdm(seeds + test_seeds, desc="render", mininterval=10):
        hm = runner.observe(s)
        maps[s] = (hm.color, hm.depth)
    table["mis"] = [misalignment_deg(runner, int(s), int(k), rotations)
                    for s, k in zip(table.seed, table.rotation, strict=True)]
    near = table.mis <= 180 / rotations
    print(f"{args.run}: {len(table)} transitions, mean reward {table.reward.mean():.3f}; "
          f"jaws within {180 / rotations:.2f} deg: {near.mean():.0%} of them, mean reward "
          f"{table.reward[near].mean():.3f}, beyond: {table.reward[~near].mean():.3f}")
    order = np.random.default_rng(args.net_seed).integers(len(table), size=args.steps)
    for mode, precision in itertools.product(args.rotate, args.precision):
        network_cfg = override(cfg, "network.precision", precision).network
        agent = GraspAgent(network_cfg, cfg.agent, seed=args.net_seed, rotate=mode)
        t0 = time.perf_counter()
        for n in tqdm(order, desc=f"fit {mode} {precision}", mininterval=10):
            row = table.iloc[int(n)]
            color, depth = maps[int(row.seed)]
            agent.update(Transition(color, depth, (int(row.rotation), int(row.row),
                                                   int(row.col)), float(row.reward), done=True))
        fit = time.perf_counter() - t0
        m = greedy_misalignments(agent, runner, maps, test_seeds)
        print(summary(f"rotate={mode}, {precision}, {args.steps} steps", m, rotations, fit),
              flush=True)
    if args.skip_own:
        return
    _, _, agent, episodes = load_trained_agent(args.run)
    m = greedy_misalignments(agent, runner, maps, test_seeds)
    print(summary(f"the run's own, {episodes} episodes", m, rotations, 0.0))


if __name__ == "__main__":
    main()
