"""What keeping scene seeds instead of heightmaps costs training, and what it saves on disk.

Run: ``.venv/bin/python benchmarks/bench_replay.py [--scenes 200] [--steps 8]``.

At the ``paper`` profile's settings with the light backbone (R = 16, 224 x 224, replay capacity
5000) it prints

* the learning step of one episode (its own update, the add, ``agent.replay_batch`` = 1
  prioritised replay) with a replay that keeps heightmaps (before) and one that keeps scene
  seeds and re-renders them (after, LRU cache of ``DEFAULT_CACHE`` maps), on the same
  ``--scenes`` real scenes (``EpisodeRunner.observe``) and the same draws; the two runs must
  give identical losses (the re-rendered maps are the stored ones);
* the parts: one ``get`` from each buffer (a render on a cache miss, a copy on a hit) and one
  render;
* the cache's hit rate over a simulated 5000-episode run of the replay draws alone (the
  surprise of a new transition uniform in [0, 1), a replayed one's shrinking to a uniform
  fraction of itself: a model, not a measurement of training);
* the checkpoint size per transition and the size of a 5000-grasp checkpoint (networks,
  optimiser with its momentum buffers, full replay), for both kinds of replay.

Figures only, no assertions. Wall times on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from vgs.assembly.episode import EpisodeRunner
from vgs.config import override, profile
from vgs.experiments.train import TrainState, episode_seed, save_checkpoint, scene_renderer
from vgs.grasping.agent import DeltaQMonitor, GraspAgent
from vgs.grasping.replay import DEFAULT_CACHE, ReplayBuffer, Transition


def learning_steps(cfg, scenes, maps, render, steps: int, keep_scenes: bool
                   ) -> tuple[list[float], list[float]]:
    """Seconds per episode's learning step and the losses, after the buffer holds ``scenes``."""
    agent = GraspAgent(cfg.network, cfg.agent, seed=0)
    replay = (ReplayBuffer(cfg.agent.replay_capacity, render=render) if keep_scenes
              else ReplayBuffer(cfg.agent.replay_capacity))
    rng = np.random.default_rng(0)
    n = len(scenes)
    for e, s in enumerate(scenes[:-steps]):  # fill without learning (surprise: a model)
        color, depth = maps[s]
        replay.add(Transition(color, depth, (e % 16, 112, 112), 0.3 * (e % 2), scene=s),
                   float(rng.uniform()))
    times, losses = [], []
    for e in range(n - steps, n):
        s = scenes[e]
        color, depth = maps[s]
        t0 = time.perf_counter()
        transition = Transition(color, depth, (e % 16, 112, 112), 0.3 * (e % 2), scene=s)
        stats = agent.update(transition)
        replay.add(transition, stats["delta_q"])
        replays = agent.replay_update(replay, rng)
        times.append(time.perf_counter() - t0)
        losses += [stats["loss"], *(r["loss"] for r in replays)]
    return times, losses


def get_seconds(replay: ReplayBuffer, slots: list[int]) -> float:
    t0 = time.perf_counter()
    for i in slots:
        replay.get(i)
    return (time.perf_counter() - t0) / len(slots)


def simulated_hit_rate(episodes: int = 5000, capacity: int = 5000,
                       cache: int = DEFAULT_CACHE) -> float:
    replay = ReplayBuffer(capacity, render=lambda s: (np.zeros((2, 2, 3), np.uint8),
                                                       np.zeros((2, 2), np.float32)),
                          cache_size=cache)
    rng = np.random.default_rng(1)
    blank = np.zeros((2, 2, 3), np.uint8), np.zeros((2, 2), np.float32)
    for e in range(episodes):
        replay.add(Transition(*blank, (0, 0, 0), 0.0, scene=e), float(rng.uniform()))
        slot = replay.sample_index(rng)
        replay.get(slot)
        replay.update_surprise(slot, replay.surprise(slot) * float(rng.uniform()))
    return replay.cache_hits / max(1, replay.cache_hits + replay.renders)


def checkpoint_sizes(cfg, keep_scenes: bool, size: int, n: int) -> tuple[int, int]:
    """(bytes with an empty replay, bytes with ``n`` transitions) of a light-backbone run."""
    agent = GraspAgent(cfg.network, cfg.agent, seed=0)
    color = np.zeros((size, size, 3), np.uint8)
    depth = np.zeros((size, size), np.float32)
    agent.update(Transition(color, depth, (0, 5, 5), 1.0))  # momentum buffers
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for count in (0, n):
            replay = (ReplayBuffer(cfg.agent.replay_capacity, render=lambda s: (color, depth))
                      if keep_scenes else ReplayBuffer(cfg.agent.replay_capacity))
            for e in range(count):
                replay.add(Transition(color, depth, (e % 16, 5, 5), 0.3, scene=e), 0.1)
            path = Path(tmp) / "c.pt"
            save_checkpoint(path, agent, replay, TrainState(count),
                            DeltaQMonitor.from_config(cfg.agent))
            out.append(path.stat().st_size)
    return out[0], out[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=200)
    parser.add_argument("--steps", type=int, default=8)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    # The rotation action (R = 16), whose actions (k, i, j) the transitions below carry.
    cfg = override(override(profile("paper"), "network.backbone", "light"), "network.action",
                   "rotation")
    runner = EpisodeRunner(cfg)
    render = scene_renderer(runner)
    scenes = [episode_seed(0, e) for e in range(args.scenes)]
    t0 = time.perf_counter()
    maps = {s: render(s) for s in scenes}
    render_s = (time.perf_counter() - t0) / len(scenes)
    print(f"paper profile, light backbone, R = {cfg.network.num_rotations}, "
          f"{cfg.cell.camera.size} px, {args.scenes} scenes, torch threads {args.threads}")
    print(f"render one scene's heightmaps (EpisodeRunner.observe): {render_s * 1000:.1f} ms")

    before, loss_b = learning_steps(cfg, scenes, maps, render, args.steps, keep_scenes=False)
    after, loss_a = learning_steps(cfg, scenes, maps, render, args.steps, keep_scenes=True)
    print(f"learning step per episode (update + add + 1 replay), median of {args.steps}: "
          f"maps {statistics.median(before):.3f} s, scenes {statistics.median(after):.3f} s "
          f"(mean {statistics.mean(before):.3f} vs {statistics.mean(after):.3f} s)")
    print(f"losses identical: {loss_a == loss_b}")

    maps_buf = ReplayBuffer(cfg.agent.replay_capacity)
    scene_buf = ReplayBuffer(cfg.agent.replay_capacity, render=render, cache_size=0)
    cached = ReplayBuffer(cfg.agent.replay_capacity, render=render)
    for s in scenes[:DEFAULT_CACHE]:
        t = Transition(*maps[s], (0, 0, 0), 0.0, scene=s)
        for buf in (maps_buf, scene_buf, cached):
            buf.add(t, 0.1)
    slots = list(range(min(DEFAULT_CACHE, len(scenes))))
    print(f"one get: maps {get_seconds(maps_buf, slots) * 1000:.2f} ms, scenes on a cache hit "
          f"{get_seconds(cached, slots) * 1000:.2f} ms, on a miss (render) "
          f"{get_seconds(scene_buf, slots) * 1000:.1f} ms")
    print(f"simulated cache hit rate over 5000 episodes (cache {DEFAULT_CACHE}): "
          f"{simulated_hit_rate():.1%}")

    capacity = cfg.agent.replay_capacity
    for keep, n in ((False, 100), (True, capacity)):  # maps: 100 stored, the rest projected
        empty, full = checkpoint_sizes(cfg, keep, cfg.cell.camera.size, n)
        per = (full - empty) / n
        kind = "scenes" if keep else "maps"
        print(f"checkpoint ({kind}): networks + optimiser {empty / 1e6:.2f} MB, {per:.0f} B per "
              f"transition (measured on {n}), {capacity}-grasp checkpoint "
              f"{(empty + per * capacity) / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
