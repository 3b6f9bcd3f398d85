"""Training's parallel episodes, locally and on Ray, and the projected wall time of the
``paper`` protocol with DenseNet-121 here and per added 16-core node (issue 18, item 3).

Run: ``.venv/bin/python benchmarks/bench_train.py [--episodes 3] [--no-ray] [--backbone B]``
(about 2-3 min on 2 cores).

Prints, all measured on this machine with the ``paper`` profile's cell:

* the simulation of one training episode in one process, its grasp already chosen: an
  exploration grasp (a random pixel on the peg, as in the first ``agent.random_episodes``) and a
  centre grasp (a grasp that holds, so the assembly runs: the cost of a greedy episode once the
  policy grasps well, and of a test episode);
* the learner's share of one episode: rendering the heightmap, one greedy decision (the
  profile's network, 224 x 224) and one update with its replay, DenseNet-121 (``--backbone``)
  on one CPU thread;
* the wall time of the training pool (``train.parallel_episodes`` = 2) on a batch of centre
  grasps, local processes and Ray actors (start-up excluded);
* the projection of the ``paper`` protocol: 2 policies x 5000 training episodes (1000 random)
  and 1000 tests x 3 conditions x 2 policies (the centre reference and the sweep not counted).

Model of the projection (its assumptions, printed with it):

* here (c cores): all work divides over the cores: training = episodes x (learner at 1 thread +
  simulation) / c, the two runs side by side; evaluation = tests x (simulation + decision at 1
  thread) / c (the test workers decide themselves);
* with n added 16-core nodes: the two policies train side by side, each with 8 n Ray actors
  for the simulation of its episodes (``vgs train --backend ray``, ``train.parallel_episodes =
  8 n``); each network (decisions and updates) stays on this node on one core, as measured, and
  does not overlap the simulation (the loop chooses a batch, waits for its physics, then
  updates): training = 5000 x (learner + simulation / (8 n)). Evaluation runs on c + 16 n
  workers, each deciding on one core. More threads for the learner on a larger node, or a GPU,
  would shorten the learner's part; that is not measured here (``benchmarks/bench_gpu_node.sh``
  measures a GPU node: docs/training.md). Ray's
  per-call overhead and the transfer of the configuration are left out (the pool measurement
  shows their size here), and the simulation is assumed to scale with the cores (the machine
  probe of ``bench_eval.py`` shows how far it does here).

Figures only, no assertions; wall times on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from bench_eval import network_step_seconds  # this folder (the script's) is on sys.path
from vgs.assembly.episode import EpisodeRunner, center_policy
from vgs.config import BACKBONES, override, profile
from vgs.grasping.actions import peg_mask, rotation_angle
from vgs.rollout.episodepool import EpisodeWorker, GraspTask, TrainingPool
from vgs.rollout.policies import pixel_command
from vgs.runfolder.trainfolder import episode_seed

NODE_CORES = 16


def exploration_task(runner: EpisodeRunner, seed: int, rotations: int) -> GraspTask:
    """A training episode's exploration grasp: a random pixel on the peg, a random rotation."""
    hm = runner.observe(seed)
    rng = np.random.default_rng([seed, 3])
    rows, cols = np.nonzero(peg_mask(hm.depth))
    i = int(rng.integers(len(rows)))
    k = int(rng.integers(rotations))
    return GraspTask(seed, pixel_command(hm, int(rows[i]), int(cols[i]),
                                         rotation_angle(k, rotations)))


def centre_task(runner: EpisodeRunner, seed: int) -> GraspTask:
    return GraspTask(seed, center_policy()(runner.observe(seed)))


def simulation_seconds(worker: EpisodeWorker, tasks: list[GraspTask]) -> float:
    """Mean seconds of one episode's physics in this process."""
    worker.grasp(tasks[0])  # warm-up: the cell compiles
    t0 = time.perf_counter()
    for task in tasks:
        worker.grasp(task)
    return (time.perf_counter() - t0) / len(tasks)


def pool_seconds(cfg, tasks: list[GraspTask], backend: str) -> float:
    """Wall seconds of the training pool (2 workers) on ``tasks``, start-up excluded."""
    with TrainingPool(cfg, 2, backend) as pool:
        pool.run(tasks[:2])  # start-up and cell compilation outside the timing
        t0 = time.perf_counter()
        pool.run(tasks)
        return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=3,
                        help="episodes per simulation measurement (default: %(default)s)")
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray pool measurement")
    parser.add_argument("--backbone", choices=BACKBONES, default="densenet121",
                        help="the learner's backbone (default: %(default)s, the paper's)")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    cfg = override(profile("paper"), "network.backbone", args.backbone)
    print(f"machine: {cores} CPU cores; load average before: {os.getloadavg()[0]:.2f}")

    runner = EpisodeRunner(cfg)
    seeds = [episode_seed(cfg.seed, e) for e in range(args.episodes + 1)]
    runner.observe(seeds[0])
    t0 = time.perf_counter()
    for seed in seeds:
        runner.observe(seed)
    observe = (time.perf_counter() - t0) / len(seeds)
    rotations = cfg.network.num_rotations
    explore = [exploration_task(runner, s, rotations) for s in seeds]
    centre = [centre_task(runner, s) for s in seeds]
    worker = EpisodeWorker(cfg)
    sim_explore = simulation_seconds(worker, explore)
    sim_centre = simulation_seconds(worker, centre)
    print(f"simulation of one training episode (one process): exploration grasp "
          f"{sim_explore:.2f} s, centre grasp {sim_centre:.2f} s; heightmap {observe:.2f} s")

    update1, decide1 = network_step_seconds(cfg.network, 1)
    print(f"{args.backbone} ({cfg.network.action} action, {cfg.network.q_maps} Q map(s), 224 px, "
          f"1 thread): update with replay "
          f"{update1:.2f} s, decision {decide1:.2f} s")

    if not args.no_ray:
        batch = centre[:4]
        local = pool_seconds(cfg, batch, "local")
        line = f"training pool, 2 workers, {len(batch)} centre-grasp episodes: local {local:.1f} s"
        try:
            on_ray = pool_seconds(cfg, batch, "ray")
            line += f", Ray {on_ray:.1f} s (Ray / local = {on_ray / local:.2f})"
        except ImportError:
            line += "; Ray not installed"
        print(line + f"; one process would take about {len(batch) * sim_centre:.1f} s")

    tr = cfg.train.episodes
    greedy = 1.0 - cfg.agent.random_episodes / tr
    sim_train = (cfg.agent.random_episodes * sim_explore
                 + (tr - cfg.agent.random_episodes) * sim_centre) / tr
    n_train = 2 * tr
    n_test = cfg.eval.episodes * 3 * 2
    learner1 = observe + greedy * decide1 + update1
    print(f"paper protocol, {args.backbone}: {n_train} training episodes (2 policies x {tr}, "
          f"{greedy:.0%} greedy), {n_test} test episodes (1000 x 3 conditions x 2 policies)")
    print(f"  per training episode: simulation {sim_train:.2f} s (exploration and centre "
          f"grasps weighted), learner {learner1:.2f} s (heightmap, {greedy:.0%} of a decision, "
          f"update); per test episode {sim_centre + decide1:.2f} s")
    train_here = n_train * (learner1 + sim_train) / cores / 3600
    eval_here = n_test * (sim_centre + decide1) / cores / 3600
    print(f"  here ({cores} cores, all work divided over them): training {train_here:.1f} h + "
          f"evaluation {eval_here:.1f} h = {train_here + eval_here:.1f} h")
    for nodes in (1, 2, 4, 8, 16):
        workers = NODE_CORES * nodes
        train_h = tr * (learner1 + sim_train / (workers // 2)) / 3600
        eval_h = n_test * (sim_centre + decide1) / (cores + workers) / 3600
        print(f"  + {nodes:2d} node(s) of {NODE_CORES} cores ({workers // 2} Ray actors per "
              f"policy): training {train_h:.1f} h + evaluation {eval_h:.2f} h = "
              f"{train_h + eval_h:.1f} h")
    print(f"  limit (the learner alone): training {tr * learner1 / 3600:.1f} h; the network's "
          "decisions and updates stay on this node, so more nodes stop helping once "
          "simulation / (8 n) is small beside them")


if __name__ == "__main__":
    main()
