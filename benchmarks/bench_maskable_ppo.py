"""MaskablePPO learning to grasp the peg in ``vgs/GraspAssemble-v0`` (docs/agents.md's recipe).

Run: ``.venv/bin/python benchmarks/bench_maskable_ppo.py --steps 2048 --seed 0 [--block 256]
[--eval 100] [--no-unmasked] [--no-per-dimension] [--n-steps 128]``; needs
``stable-baselines3`` and ``sb3-contrib``.

The environment: the ``quick`` profile, a 64 x 64 heightmap of 5 mm pixels
(:data:`OVERRIDES`: the peg is about 6 x 20 pixels, 3 % of the image, against 224 x 224 of
2 mm by default), grasp-only episodes (``assemble=False``, reward r_G = 0.3 for a held grasp,
0 otherwise), the flat action ``Discrete(64 x 64)`` of :class:`vgs.envs.masking.FlatGraspAction`
with the exact mask of the peg's pixels.

Prints, per block of ``--block`` training steps (one step is one episode), the share of
episodes whose grasp held for

* MaskablePPO with the exact mask (``MultiInputPolicy``: a CNN per image; every allowed
  pixel is on the peg),
* MaskablePPO with the environment's own per-dimension mask of the ``MultiDiscrete`` action
  (:meth:`GraspAssembleEnv.action_masks`: the rows and the columns that hold a peg pixel, the
  peg's bounding box, mostly table for a diagonal peg: the agent must learn where the peg is
  inside it), and
* the same PPO without masks (unless ``--no-unmasked``),

then a deterministic evaluation of each on ``--eval`` fresh seeded scenes (the same scenes for
every policy) beside a random pixel on the peg (uniform over the exact mask), a random pixel of
the bounding box (a row and a column drawn from the per-dimension mask) and the centroid of the
peg's pixels: the share of held grasps and the mean |grasp offset| [mm] from the peg's middle
(ground truth, of the held grasps). Training episodes and the evaluation use different seeds.
Figures only, no assertions.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch
from sb3_contrib import MaskablePPO
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback

from vgs.envs.callbacks import EpisodeLogger
from vgs.envs.grasp_assemble import GraspAssembleEnv
from vgs.envs.masking import FlatGraspAction

OVERRIDES = {"cell.camera.size": 64, "cell.camera.pixel_size": 0.005}
PPO_KWARGS: dict[str, Any] = {"n_steps": 128, "batch_size": 64, "n_epochs": 4,
                              "learning_rate": 3e-4, "verbose": 0}
EVAL_SEED = 10_000  # the evaluation's scenes: seeds from EVAL_SEED + seed on

Act = Callable[[dict[str, np.ndarray], Any], Any]  # observation, env -> action


def make_env(seed: int, flat: bool = True) -> Any:
    """The benchmark's environment (module docstring), seeded: the flat action
    (:class:`FlatGraspAction`) or, with ``flat=False``, the ``MultiDiscrete`` one."""
    env: Any = GraspAssembleEnv("quick", mode="baseline", overrides=OVERRIDES, assemble=False)
    if flat:
        env = FlatGraspAction(env)
    env.reset(seed=seed)
    return env


class BlockLog(BaseCallback):
    """Counts held grasps per block of training steps; prints each block as it ends."""

    def __init__(self, name: str, block: int) -> None:
        super().__init__()
        self.name, self.block = name, block
        self.grasps: list[bool] = []
        self.start = time.perf_counter()

    def _on_step(self) -> bool:
        for info in self.locals["infos"]:
            if "record" in info:
                self.grasps.append(bool(info["record"]["grasp_success"]))
                n = len(self.grasps)
                if n % self.block == 0:
                    share = np.mean(self.grasps[n - self.block:])
                    print(f"  {self.name}: steps {n - self.block:5d}-{n - 1:5d} grasped "
                          f"{share:.3f}  ({time.perf_counter() - self.start:.0f} s)",
                          flush=True)
        return True


VARIANTS = {  # name: (MaskablePPO, flat action)
    "MaskablePPO, exact mask": (True, True),
    "MaskablePPO, per-dimension mask": (True, False),
    "PPO, no mask": (False, True),
}


def train(name: str, steps: int, seed: int, block: int, n_steps: int = 128
          ) -> tuple[Any, float]:
    """A trained :data:`VARIANTS` ``name`` and its wall time [s] (``n_steps`` steps per
    rollout)."""
    masked, flat = VARIANTS[name]
    env = make_env(seed, flat)
    algo = MaskablePPO if masked else PPO
    kwargs = {**PPO_KWARGS, "n_steps": n_steps, "batch_size": min(64, n_steps)}
    model = algo("MultiInputPolicy", env, seed=seed, **kwargs)
    start = time.perf_counter()
    model.learn(total_timesteps=steps, callback=[EpisodeLogger(), BlockLog(name, block)])
    return model, time.perf_counter() - start


def evaluate(act: Act, episodes: int, seed: int, flat: bool = True) -> tuple[float, float]:
    """(share of held grasps, mean |grasp offset| [mm] of the held ones) on the evaluation's
    scenes."""
    env = make_env(EVAL_SEED + seed, flat)
    obs, _ = env.reset(seed=EVAL_SEED + seed)
    held, offsets = [], []
    for _ in range(episodes):
        _, _, _, _, info = env.step(act(obs, env))
        record = info["record"]
        held.append(bool(record["grasp_success"]))
        if record["grasp_success"]:
            offsets.append(abs(record["grasp_offset_mm"]))
        obs, _ = env.reset()
    return float(np.mean(held)), float(np.mean(offsets)) if offsets else float("nan")


def revision() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True, cwd=Path(__file__).parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=2048, help="training steps (episodes)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--block", type=int, default=256, help="steps per printed block")
    parser.add_argument("--eval", type=int, default=100, help="evaluation episodes")
    parser.add_argument("--no-unmasked", action="store_true", help="skip the unmasked PPO")
    parser.add_argument("--no-per-dimension", action="store_true",
                        help="skip MaskablePPO with the per-dimension mask")
    parser.add_argument("--n-steps", type=int, default=128,
                        help="PPO's steps per rollout (default: %(default)s)")
    args = parser.parse_args()
    if min(args.steps, args.block, args.eval) < 1 or args.n_steps < 2:
        parser.error("--steps, --block and --eval must be >= 1, --n-steps >= 2")
    torch.set_num_threads(1)
    print(f"host {platform.node()} ({os.cpu_count()} cores), revision {revision()}, torch "
          f"{torch.__version__}, steps {args.steps}, seed {args.seed}", flush=True)
    rng = np.random.default_rng(args.seed)

    def random_on_peg(_obs: dict[str, np.ndarray], env: Any) -> Any:
        return int(rng.choice(np.flatnonzero(env.action_masks())))

    def random_in_box(_obs: dict[str, np.ndarray], env: Any) -> Any:
        mask = env.action_masks()  # the MultiDiscrete env's: maps, rows, columns
        n, h = int(env.action_space.nvec[0]), int(env.action_space.nvec[1])
        maps, rows, cols = mask[:n], mask[n:n + h], mask[n + h:]
        return np.array([rng.choice(np.flatnonzero(m)) for m in (maps, rows, cols)])

    def centroid(_obs: dict[str, np.ndarray], env: Any) -> Any:
        pixels = np.argwhere(env.get_wrapper_attr("pixel_mask")())
        row, col = pixels[np.argmin(((pixels - pixels.mean(axis=0)) ** 2).sum(axis=1))]
        return env.flat(0, int(row), int(col))

    # name: (act, flat action)
    policies: dict[str, tuple[Act, bool]] = {
        "random pixel on the peg": (random_on_peg, True),
        "random pixel of its box": (random_in_box, False),
        "centroid of the peg's pixels": (centroid, True)}
    skip = {"PPO, no mask"} if args.no_unmasked else set()
    if args.no_per_dimension:
        skip.add("MaskablePPO, per-dimension mask")
    for name, (masked, flat) in VARIANTS.items():
        if name in skip:
            continue
        model, wall = train(name, args.steps, args.seed, args.block, args.n_steps)
        print(f"  {name}: {args.steps} steps in {wall:.0f} s ({wall / args.steps:.3f} s/step)",
              flush=True)

        def learned(obs: dict[str, np.ndarray], env: Any, model: Any = model,
                    masked: bool = masked) -> Any:
            kwargs = {"action_masks": env.action_masks()} if masked else {}
            action = model.predict(obs, deterministic=True, **kwargs)[0]
            return np.asarray(action).astype(np.int64) if action.ndim else int(action)

        policies[name] = (learned, flat)
    print(f"evaluation, {args.eval} fresh scenes (seed {EVAL_SEED + args.seed}), deterministic:")
    for name, (act, flat) in policies.items():
        share, offset = evaluate(act, args.eval, args.seed, flat)
        print(f"  {name:32s} grasped {share:.3f}  mean |offset| {offset:5.1f} mm", flush=True)


if __name__ == "__main__":
    main()
