"""Speed of evaluation at scale and of the reproduction profiles.

Run: ``.venv/bin/python benchmarks/bench_eval.py [--episodes 24] [--quick] [--quick-dir DIR]``.

Prints

* episodes per second of ``evaluate`` with 1 and 2 local worker processes on the same test
  episodes (centre grasp, nominal peg), and the scaling efficiency
  ``(episodes/s with 2) / (2 x episodes/s with 1)`` (target >= 0.8 on a 2-core machine), and a
  machine probe: how much slower MuJoCo alone steps the cell when two processes do it at once
  (what the machine takes from each worker, whatever vgs does);
* Ray's wall time over local processes' for the same episodes with 2 workers (start-up of the
  local Ray instance included, and without it);
* the wall time of ``vgs reproduce --profile quick`` (``--quick`` runs it in a subprocess;
  ``--quick-dir`` reads the stage times of a finished run) (target: 15 minutes);
* the ``paper-light`` protocol (issue 18: light backbone, R = 16, input rotation, bfloat16, the
  baseline's training grasps without assembly, VGS's training assemblies stopped at the
  threshold, 1000 tests per learned policy and condition) projected from parts measured here in
  CPU seconds of one process: a whole episode, the same stopped at the median of their assembly
  times (the threshold's percentile), a grasp without assembly (grasps 0-35 mm from the centre
  along the axis, like the sweep's), a replay's re-rendering, one training step and one greedy
  decision; core-hours divided by the cores times the measured scaling efficiency
  (target 2.5 h); ``--light-dir`` prints a finished run's stage wall times beside it;
* an estimate of the ``paper`` profile's wall time on this machine, from measured parts: the
  mean wall time of a training episode's simulation (from the quick run's ``episodes.csv``,
  network time removed), one training step and one greedy decision of each backbone at the
  paper's settings (the rotation action, R = 16, 224 x 224), and the measured evaluation
  throughput
  (targets: 8 h with DenseNet-121, 3 h with the light backbone; the features rotation mode of
  DenseNet-121 and ``network.precision = bfloat16`` are listed too).

One worker runs in this process; two workers are a spawned process pool, whose start-up
(imports, cell compilation) counts against them.

Figures only, no assertions. Wall times on a shared machine are noisy: ratios are more stable.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from vgs.assembly.episode import EpisodeRunner, center_policy, offset_policy
from vgs.config import NetworkConfig, profile
from vgs.experiments.evaluate import EvalSpec, evaluate_many
from vgs.grasping.replay import cache_size_for


def throughput(episodes: int, workers: int, backend: str, seed: int = 7) -> tuple[float, float]:
    """(wall seconds, summed per-episode seconds) of ``episodes`` centre-grasp test episodes."""
    cfg = profile("paper")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        (df,) = evaluate_many(cfg, [(EvalSpec("center", "nominal", episodes, seed),
                                     Path(tmp))], workers=workers, backend=backend,
                              progress=False)
        wall = time.perf_counter() - t0
    return wall, float(df["wall_s"].sum())


def _step_cell(steps: int) -> float:
    """CPU-bound probe: seconds to step the cell ``steps`` times, the arm holding still."""
    import mujoco

    from vgs.sim.cell import HOME_Q, Cell

    cfg = profile("paper")
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(0))
    cell.data.ctrl[cell.ids.arm_act] = HOME_Q
    t0 = time.perf_counter()
    mujoco.mj_step(cell.model, cell.data, steps)
    return time.perf_counter() - t0


def machine_contention(steps: int = 60_000) -> float:
    """Slowdown of MuJoCo alone when two processes step the cell at once (1.00 = none): what
    this machine takes from each worker when both cores are busy, whatever vgs does."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(2, mp_context=mp.get_context("spawn")) as pool:
        pool.submit(_step_cell, 100).result()  # start-up outside the timing
        alone = pool.submit(_step_cell, steps).result()
        both = [f.result() for f in [pool.submit(_step_cell, steps) for _ in range(2)]]
    return float(np.mean(both)) / alone


def ray_startup() -> float:
    """Seconds to start and stop a local Ray instance."""
    import ray

    t0 = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    ray.shutdown()
    return time.perf_counter() - t0


def network_step_seconds(network: NetworkConfig, threads: int) -> tuple[float, float]:
    """(one training update incl. one replay, one greedy decision) of ``network`` on a 224 px
    heightmap [s].

    Each is timed after one untimed call of its own (oneDNN builds its kernels on the first
    call, which in bfloat16 took longer than the call itself); the decision is the median of
    three."""
    import torch

    from vgs.config import AgentConfig
    from vgs.grasping.agent import GraspAgent
    from vgs.grasping.replay import ReplayBuffer, Transition

    torch.set_num_threads(threads)
    agent = GraspAgent(network, AgentConfig())
    rng = np.random.default_rng(0)
    color = rng.integers(0, 255, (224, 224, 3), dtype=np.uint8)
    depth = np.zeros((224, 224), np.float32)
    depth[100:115, 80:130] = 0.03
    tr = Transition(color, depth, (min(3, network.q_maps - 1), 107, 100), 0.3, done=True)
    replay = ReplayBuffer(10)
    agent.update(tr)  # warm-up
    t0 = time.perf_counter()
    stats = agent.update(tr)
    replay.add(tr, stats["delta_q"])
    agent.replay_update(replay, rng)
    update = time.perf_counter() - t0
    agent.q_values(color, depth)  # warm-up
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        agent.q_values(color, depth)
        times.append(time.perf_counter() - t0)
    return update, float(np.median(times))


def light_parts(episodes: int) -> dict[str, float]:
    """CPU seconds (this process) per episode of the ``paper-light`` protocol's parts."""
    cfg = profile("paper-light")
    runner = EpisodeRunner(cfg)
    runner.run(10_000, center_policy())  # compile the cell, warm the caches

    def cpu(call, *args, **kwargs) -> tuple[float, object]:
        t0 = time.process_time()
        out = call(*args, **kwargs)
        return time.process_time() - t0, out

    grasps = [(seed, offset_policy(float(off)))
              for seed, off in enumerate(np.linspace(-0.035, 0.035, episodes))]
    whole, times = [], []
    for seed, policy in grasps:
        c, (rec, _, _) = cpu(runner.run, seed, policy)
        whole.append(c)
        if rec.success:
            times.append(rec.assembly_time)
    limit = float(np.percentile(times, cfg.reward.threshold_percentile))
    cut = [cpu(runner.run, seed, policy, time_limit=limit)[0] for seed, policy in grasps]
    grasp = [cpu(runner.run, seed, policy, assemble=False)[0] for seed, policy in grasps]
    render = [cpu(runner.observe, seed)[0] for seed, _ in grasps]
    update, decide = network_step_seconds(cfg.network, 1)
    return {"whole": float(np.mean(whole)), "cut": float(np.mean(cut)), "limit_s": limit,
            "grasp": float(np.mean(grasp)), "render": float(np.mean(render)),
            "update": update, "decide": decide,
            "success": len(times) / episodes}


def light_projection(parts: dict[str, float], cores: int, efficiency: float) -> None:
    """Print the ``paper-light`` protocol's projected core-hours and wall time."""
    cfg = profile("paper-light")
    n, n_random = cfg.train.episodes, cfg.agent.random_episodes
    greedy = n - n_random
    # A replay renders its maps only when the training cache cannot hold the whole buffer.
    cached = cache_size_for(cfg.agent.replay_capacity, cfg.cell.camera.size) >= min(
        n, cfg.agent.replay_capacity)
    network = n * (parts["update"] + (0.0 if cached else parts["render"])) + (
        greedy * parts["decide"])
    base_sim = n * (parts["grasp"] if not cfg.train.assemble_baseline else parts["whole"])
    vgs_sim = n_random * parts["whole"] + greedy * (
        parts["cut"] if cfg.train.stop_at_threshold else parts["whole"])
    n_tests = 2 * cfg.eval.episodes * len(cfg.reproduce.conditions)
    tests = n_tests * (parts["whole"] + parts["decide"])
    rows = [("baseline training", network + base_sim), ("VGS training", network + vgs_sim),
            (f"{n_tests} tests", tests)]
    total = sum(c for _, c in rows)
    print(f"paper-light protocol ({cfg.network.backbone}, R = {cfg.network.num_rotations}, "
          f"rotate={cfg.network.rotate}, {cfg.network.precision}; {n} grasps per policy, "
          f"{n_tests} tests), "
          "from parts measured in CPU seconds of one process:")
    print(f"  episode: whole {parts['whole']:.2f} s ({parts['success']:.0%} assembled), "
          f"stopped at {parts['limit_s']:.1f} s {parts['cut']:.2f} s, grasp only "
          f"{parts['grasp']:.2f} s; replay render {parts['render']:.3f} s "
          f"({'none: the cache holds the buffer' if cached else 'every replay'}), training step "
          f"{parts['update']:.3f} s, decision {parts['decide']:.3f} s")
    for name, core_s in rows:
        print(f"  {name:<18} {core_s / 3600:5.2f} core-h")
    wall = total / (cores * efficiency) / 3600
    print(f"  total {total / 3600:.2f} core-h -> {wall:.2f} h on {cores} cores at scaling "
          f"efficiency {efficiency:.2f} (target 2.5 h)")


def quick_wall(run_quick: bool, quick_dir: Path | None) -> tuple[float | None, Path | None]:
    if run_quick:
        out = Path(tempfile.mkdtemp()) / "quick"
        vgs = str(Path(sys.executable).with_name("vgs"))
        t0 = time.perf_counter()
        subprocess.run([vgs, "reproduce", "--profile", "quick", "--out", str(out),
                        "--no-progress"], check=True)
        return time.perf_counter() - t0, out
    if quick_dir is not None:
        walls = json.loads((quick_dir / "reproduce.json").read_text())["stage_wall_s"]
        return float(sum(walls.values())), quick_dir
    return None, None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=24,
                        help="test episodes per measurement (few episodes exaggerate the pool's "
                             "start-up and the idle worker at the end)")
    parser.add_argument("--quick", action="store_true",
                        help="also run `vgs reproduce --profile quick` (about 15 min)")
    parser.add_argument("--quick-dir", type=Path,
                        help="a finished quick reproduction to read stage times from")
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray measurement")
    parser.add_argument("--probe-steps", type=int, default=60_000,
                        help="physics steps of the machine probe per process")
    parser.add_argument("--light-episodes", type=int, default=8,
                        help="episodes per measured part of the paper-light projection (0: skip)")
    parser.add_argument("--light-dir", type=Path,
                        help="a finished `vgs reproduce --profile paper-light` folder: print its "
                             "stage wall times beside the projection")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    print(f"machine: {cores} CPU cores; load average before: {os.getloadavg()[0]:.2f}")

    w1, s1 = throughput(args.episodes, 1, "local")
    w2, s2 = throughput(args.episodes, 2, "local")
    eps1, eps2 = args.episodes / w1, args.episodes / w2
    print(f"local, 1 worker : {w1:7.1f} s wall, {eps1:.3f} episodes/s "
          f"(sum of episode times {s1:.1f} s)")
    print(f"local, 2 workers: {w2:7.1f} s wall, {eps2:.3f} episodes/s "
          f"(sum of episode times {s2:.1f} s)")
    print(f"scaling efficiency at 2 workers: {eps2 / (2 * eps1):.2f} (target >= 0.8)")
    print(f"  per-episode time with 2 workers / with 1: {s2 / s1:.2f} "
          "(1.00 = no slowdown from sharing the machine)")
    print(f"  machine probe, MuJoCo alone in 2 processes at once / in 1: "
          f"{machine_contention(args.probe_steps):.2f}")
    if not args.no_ray:
        try:
            wr, _ = throughput(args.episodes, 2, "ray")
            start = ray_startup()
            print(f"ray, 2 workers  : {wr:7.1f} s wall; ray / local = {wr / w2:.2f} "
                  f"(start-up {start:.1f} s; without it {(wr - start) / w2:.2f})")
        except ImportError:
            print("ray: not installed (pip install 'vgs[ray]')")

    if args.light_episodes:
        light_projection(light_parts(args.light_episodes), cores, min(1.0, eps2 / (2 * eps1)))
    if args.light_dir is not None:
        doc = json.loads((args.light_dir / "reproduce.json").read_text())
        walls = doc["stage_wall_s"]
        print(f"  measured run {args.light_dir}: " + ", ".join(
            f"{k} {v / 3600:.2f} h" for k, v in walls.items())
              + f" = {sum(walls.values()) / 3600:.2f} h")

    wall, qdir = quick_wall(args.quick, args.quick_dir)
    if wall is None:
        print("quick profile: not measured (pass --quick or --quick-dir)")
        return
    print(f"quick profile: {wall / 60:.1f} min wall (target 15 min)")
    walls = json.loads((qdir / "reproduce.json").read_text())["stage_wall_s"]
    print("  stages: " + ", ".join(f"{k} {v / 60:.1f} min" for k, v in walls.items()))

    # Paper profile estimate from measured parts.
    paper = profile("paper")
    runs = [pd.read_csv(p) for p in sorted((qdir / "train").glob("*/episodes.csv"))]
    quick = profile("quick")
    q_update, q_decide = network_step_seconds(quick.network, max(1, cores // 2))
    train = pd.concat(runs)
    sim_train = float(train["wall_s"].mean()) - q_update - q_decide * float(
        (train["explored"] == 0).mean())
    evals = [pd.read_parquet(p) for p in sorted((qdir / "eval").glob("*/*/episodes.parquet"))]
    sim_eval = float(pd.concat(evals)["wall_s"].mean())
    n_policies = 2 * len(paper.reproduce.train_seeds) + len(paper.reproduce.reference_policies)
    n_eval = paper.eval.episodes * len(paper.reproduce.conditions) * n_policies
    n_sweep = paper.reproduce.sweep_offsets * paper.reproduce.sweep_trials
    greedy_share = 1.0 - paper.agent.random_episodes / paper.train.episodes
    print(f"paper profile estimate ({paper.train.episodes} training episodes per run, "
          f"{n_eval} test and {n_sweep} sweep episodes, {cores} cores):")
    print(f"  measured: simulation {sim_train:.2f} s per training episode, {sim_eval:.2f} s "
          "per test episode (one process each)")
    for backbone, rotate, precision in (("densenet121", "input", "float32"),
                                        ("densenet121", "input", "bfloat16"),
                                        ("densenet121", "features", "float32"),
                                        ("densenet121", "features", "bfloat16"),
                                        ("light", "input", "float32"),
                                        ("light", "input", "bfloat16")):
        update, decide = network_step_seconds(
            NetworkConfig(backbone=backbone, action="rotation", num_rotations=16, rotate=rotate,
                          precision=precision), max(1, cores // 2))
        per_train = sim_train + update + greedy_share * decide
        parallel = min(cores, 2 * len(paper.reproduce.train_seeds))
        train_h = 2 * len(paper.reproduce.train_seeds) * paper.train.episodes * per_train \
            / parallel / 3600
        eval_h = (n_eval * (sim_eval + decide * 2 / 3) + n_sweep * sim_eval) / cores / 3600
        target = 8 if backbone == "densenet121" else 3
        print(f"  {backbone:<11} rotate={rotate:<8} {precision:<8}: update {update:.2f} s, "
              f"decision "
              f"{decide:.2f} s -> training {train_h:.1f} h + evaluation {eval_h:.1f} h = "
              f"{train_h + eval_h:.1f} h (target {target} h)")


if __name__ == "__main__":
    main()
