"""Self-supervised training of the grasp network: VGS (grasp + assembly reward) or the baseline.

The loop reads top to bottom; one iteration is one episode:

1. the cell is reset with the episode's seed (``SeedSequence([seed, episode])``) and the camera
   gives the heightmap s;
2. the agent picks a pixel (i, j) epsilon-greedily (a random pixel on the peg while
   exploring); the pixel becomes the world grasp point, and the jaws close across the peg's
   axis as perceived in the heightmap (``network.action = "position"``, the paper's) or along
   theta_k of a chosen rotation k (``"rotation"``);
3. the grasp primitive and the assembly module run; the episode record comes back (the
   baseline skips the assembly with ``train.assemble_baseline`` off, and VGS stops it at the
   frozen threshold with ``train.stop_at_threshold``: neither changes a reward);
4. reward R = r_G + r_AM (paper eq. 5); r_AM only in ``vgs`` mode, when the assembly succeeded
   faster than the threshold;
5. one SGD step on the executed pixel (plus ``replay_batch`` prioritised replays);
6. a row is appended to ``episodes.csv``, scalars go to TensorBoard, and every
   ``checkpoint_every`` episodes the whole state is saved.

Bootstrap: each grasp-and-assembly ends the episode and the next peg is placed independently of
the action, so the TD target is ``y = R`` (``done=True``). Adding ``gamma max Q_tar(s')`` with an
independent s' would add the same expected constant to every action's target and change no
decision.

Threshold: ``reward.threshold_s`` if given; otherwise, during the random-exploration phase the
running ``threshold_percentile`` of the successful assembly times seen so far, frozen at the end
of that phase and written to ``threshold.json``.

Replay: the buffer keeps each transition's scene seed (the episode's seed; the peg is the
configured one), action, reward and surprise, and re-renders the heightmaps of a replayed
transition with ``runner.observe(seed)``, the path that produced them (reset with
``default_rng(seed)``, ray-cast capture without noise): bit-identical maps, so a checkpoint of
5000 transitions holds 0.3 MB of replay instead of 1.75 GB of maps. The newest transition's
maps are hashed into the checkpoint and re-rendered on resume; a host that renders them
differently is refused.

Resume: a run started again with the same ``--out`` (or the folder moved elsewhere) compares
the request with ``run.json`` (any difference but a larger ``train.episodes`` is refused, naming
the field), loads ``checkpoint.pt`` (both networks, optimiser, replay, RNG states, threshold,
episode counter; pickle-free, :mod:`vgs.checkpoint`; the heightmap replay of a
``vgs-checkpoint/2`` file is turned into scene seeds), checks the rows of ``episodes.csv``
against the plan (episode numbers and seeds), drops the rows written after that checkpoint,
and continues. A larger ``train.episodes`` extends the run: the epsilon schedule stays the one
of the first request (``schedule_episodes`` in ``run.json``), so the episodes already run keep
their meaning and the extra ones act at the final epsilon. The folder is locked
(:func:`vgs.runfolder.common.locked`) while the run works.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from vgs.assembly.episode import EpisodeRunner, GraspCommand
from vgs.assembly.record import EpisodeRecord
from vgs.checkpoint import MAX_JOURNAL_BYTES, read_regular
from vgs.columns import rounded_rows
from vgs.config import ExperimentConfig
from vgs.errors import CheckpointError, ConfigError, CorruptFileError
from vgs.grasping.agent import DeltaQMonitor, GraspAction, GraspAgent
from vgs.grasping.preprocess import peg_mask
from vgs.grasping.replay import Renderer, ReplayBuffer, Transition, cache_size_for
from vgs.grasping.rewards import MODES, episode_reward, next_threshold
from vgs.rollout.episodepool import BACKENDS, GraspTask, TrainingPool
from vgs.rollout.policies import finished_as_policy, pixel_command
from vgs.runfolder.common import check_belongs, locked, read_json, run_identity, write_json
from vgs.runfolder.folderkind import claim
from vgs.runfolder.trainfolder import (
    RECORD_COLUMNS,
    TrainState,
    check_start,
    episode_seed,
    load_checkpoint,
    open_table,
    read_rows,
    save_checkpoint,
    sha256_hex,
)
from vgs.sim.camera import Heightmap
from vgs.validate import check_config

REPLAY_CACHE: int | None = None  # replay maps kept in memory (None: replay.cache_size_for)


def scene_renderer(runner: EpisodeRunner) -> Renderer:
    """The replay's renderer: the heightmaps a training episode of that seed observed."""

    def render(seed: int) -> tuple[np.ndarray, np.ndarray]:
        hm = runner.observe(seed)
        return hm.color, hm.depth

    return render


def action_to_command(action: GraspAction, hm: Heightmap) -> GraspCommand:
    """World grasp of a pixel-wise action (:func:`vgs.rollout.policies.pixel_command`)."""
    return pixel_command(hm, action.row, action.col, action.angle)


def resolve_device(name: str) -> str:
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda" and not torch.cuda.is_available():
        raise ConfigError("train.device", "cuda requested but no GPU is available")
    return name




def train(cfg: ExperimentConfig, mode: str, out: Path, progress: bool = True,
          threads: int | None = None, position: int = 0, backend: str = "local",
          ray_address: str | None = None) -> Path:
    """Train (or resume) one policy; return the run directory.

    Args:
        cfg: Experiment configuration; on resume it must equal the one in ``run.json``, except
            for a larger ``train.episodes`` (which extends the run).
        mode: ``vgs`` or ``baseline``.
        out: Run folder.
        progress: Show a progress bar.
        threads: Torch CPU threads (default: up to 4, at most the number of cores); a
            resumed run keeps the count its ``run.json`` recorded.
        position: Line of the progress bar (several runs side by side).
        backend: Where the physics of parallel episodes (``train.parallel_episodes`` > 1)
            runs: ``local`` (spawned processes) or ``ray`` (Ray actors,
            :class:`vgs.rollout.episodepool.TrainingPool`); the table is the same.
        ray_address: Address of a running Ray cluster (``ray``; default: start a local one).

    Raises:
        ConfigError: On an unknown mode or a bad configuration (checked before anything is
            written).
        RunMismatchError: If ``out`` holds a run with another mode or configuration.
        CorruptFileError: If a file of the run cannot be read or does not fit the run
            (:class:`vgs.errors.CheckpointError` for the checkpoint).
        FolderBusyError: If another process is working in ``out``.
    """
    if mode not in MODES:
        raise ConfigError("mode", f"must be one of {MODES}, got {mode!r}")
    if backend not in BACKENDS:
        raise ConfigError("backend", f"must be one of {BACKENDS}, got {backend!r}")
    cfg = check_config(cfg)  # before anything is written
    device = resolve_device(cfg.train.device)
    if out.exists() and not out.is_dir():
        raise ConfigError("out", f"{out} is a file, not a folder")
    claim(out, "training run")
    with locked(out):
        return _train(cfg, mode, out, device, progress, threads, position, backend,
                      ray_address)


def _train(cfg: ExperimentConfig, mode: str, out: Path, device: str, progress: bool,
           threads: int | None, position: int, backend: str, ray_address: str | None) -> Path:
    # Everything is checked before anything is written: the networks can be built, the request
    # matches run.json, the checkpoint and the table fit.
    total = cfg.train.episodes
    agent = GraspAgent(cfg.network, cfg.agent, device=device, seed=cfg.seed)
    schedule, run_threads, new_meta = check_start(cfg, mode, out, threads)
    if finished_as_policy(out, total):
        return out  # finished, and kept as its final network (scripts/carry.sh)
    torch.set_num_threads(run_threads)
    runner = EpisodeRunner(cfg)
    cache = (cache_size_for(cfg.agent.replay_capacity, cfg.cell.camera.size)
             if REPLAY_CACHE is None else REPLAY_CACHE)
    replay = ReplayBuffer(cfg.agent.replay_capacity, render=scene_renderer(runner),
                          cache_size=cache)
    monitor = DeltaQMonitor.from_config(cfg.agent)
    state = TrainState(exploration_times=[])
    rng = np.random.default_rng([cfg.seed, 7])
    ckpt = out / "checkpoint.pt"
    if ckpt.exists():
        state = load_checkpoint(ckpt, agent, replay, monitor, device, root_seed=cfg.seed)
        try:
            rng.bit_generator.state = state.rng_state
        except (TypeError, ValueError, KeyError) as exc:
            raise CheckpointError(ckpt, f"holds a bad generator state ({exc})") from None
        if state.episode > total:
            raise CorruptFileError(ckpt, f"is at episode {state.episode}, beyond the run's "
                                         f"{total}")
    run_meta = new_meta if new_meta is not None else read_json(out / "run.json")
    check_belongs(state.run, run_meta, ckpt, out / "run.json")  # not another run's checkpoint
    state.run = run_identity(run_meta)
    if cfg.reward.threshold_s is not None:
        state.threshold = cfg.reward.threshold_s
    rows = read_rows(out / "episodes.csv", cfg, mode, state.episode, state.table_sha256)
    if new_meta is not None:
        write_json(out / "run.json", new_meta)

    log = _TrainLog(out, rows, mode, state.episode, total, progress, position)
    if log.writer is not None:
        log.writer.add_text("config", config_text(cfg, mode), state.episode)
    source = _EpisodeSource(cfg, agent, runner, rng, schedule, backend, ray_address,
                            lambda: _assembly_plan(cfg, mode, state))
    try:
        for episode in log.bar:
            t0 = time.perf_counter()
            record, seed, epsilon, action, hm = source.episode(episode)
            r_grasp, r_asm, threshold = _reward(cfg, mode, state, record, episode, out)
            reward = r_grasp + r_asm

            # Learning: the executed pixel, then prioritised replays.
            transition = Transition(hm.color, hm.depth, action.action, reward, done=True,
                                    scene=seed)
            stats = agent.update(transition)
            replay.add(transition, stats["delta_q"])
            agent.replay_update(replay, rng)
            monitor.update(stats["delta_q"])

            wall = time.perf_counter() - t0
            record_row = record.to_row()
            log.episode({
                "episode": episode, "mode": mode, "seed": seed, "epsilon": round(epsilon, 4),
                "explored": bool(action.explored), "rotation": action.rotation,
                "row": action.row, "col": action.col, "q_value": action.q_value,
                **{k: record_row[k] for k in RECORD_COLUMNS},
                "r_grasp": r_grasp, "r_assembly": r_asm, "reward": reward,
                "threshold_s": threshold if math.isfinite(threshold) else "",
                "loss": stats["loss"], "delta_q": stats["delta_q"], "wall_s": round(wall, 3),
            }, record, epsilon, reward, r_asm, stats, monitor, wall)

            state.episode = episode + 1
            if state.episode % cfg.train.checkpoint_every == 0 or state.episode == total:
                state.rng_state = rng.bit_generator.state
                state.table_sha256 = sha256_hex(read_regular(out / "episodes.csv",
                                                              MAX_JOURNAL_BYTES))
                save_checkpoint(ckpt, agent, replay, state, monitor)
                if not progress:  # a line per checkpoint for logs of unattended runs
                    log.checkpoint_line(state.episode)
    finally:
        log.close()
        source.close()
    if cfg.reward.threshold_s is None and state.episode >= cfg.agent.random_episodes:
        # (the same content as written when the threshold froze: restores a damaged copy)
        write_json(out / "threshold.json", _threshold_doc(cfg, state))
    write_json(out / "convergence.json",
               {"delta_q_threshold": cfg.agent.delta_q_threshold,
                "window": cfg.agent.delta_q_window, "converged": bool(monitor.converged),
                "delta_q_window_mean": monitor.mean, "delta_q_window_max": monitor.max})
    return out


def _assembly_plan(cfg: ExperimentConfig, mode: str, state: TrainState
                   ) -> tuple[bool, float | None]:
    """``(assemble, time_limit)`` for the episodes chosen now (episode ``state.episode`` on).

    The baseline skips the assembly when ``train.assemble_baseline`` is off (its reward is the
    grasp's). VGS stops an assembly at the reward threshold when ``train.stop_at_threshold`` is
    on and the threshold no longer moves: given (``reward.threshold_s``) or frozen at the end of
    the exploration phase. An assembly stopped there earns no r_AM, as it would not at its end.
    """
    if mode == "baseline":
        return cfg.train.assemble_baseline, None
    frozen = cfg.reward.threshold_s is not None or state.episode >= cfg.agent.random_episodes
    if cfg.train.stop_at_threshold and frozen and state.threshold is not None:
        return True, float(state.threshold)
    return True, None


class _EpisodeSource:
    """The episodes' grasps and records, in episode order.

    One at a time in this process; or, with ``train.parallel_episodes = K > 1``, the grasps of
    K consecutive episodes chosen with the same network and their physics run on K workers of
    the episode pool (:class:`vgs.rollout.episodepool.TrainingPool`: local processes or Ray
    actors); the updates still follow in episode order, so the table is the same.
    """

    def __init__(self, cfg: ExperimentConfig, agent: GraspAgent, runner: EpisodeRunner,
                 rng: np.random.Generator, schedule: int, backend: str,
                 ray_address: str | None,
                 plan: Callable[[], tuple[bool, float | None]]) -> None:
        self.cfg, self.agent, self.runner, self.rng = cfg, agent, runner, rng
        self.plan = plan
        self.schedule = schedule
        self.k = cfg.train.parallel_episodes
        self.collector = (TrainingPool(cfg, self.k, backend, ray_address)
                          if self.k > 1 else None)
        self.pending: dict[int, tuple[Any, int, float, GraspAction, Heightmap]] = {}

    def episode(self, episode: int
                ) -> tuple[EpisodeRecord, int, float, GraspAction, Heightmap]:
        """``(record, seed, epsilon, action, heightmap)`` of ``episode``."""
        agent, rng = self.agent, self.rng
        if self.collector is None:
            seed = episode_seed(self.cfg.seed, episode)
            epsilon = agent.epsilon(episode, self.schedule)
            chosen: dict[str, Any] = {}

            def policy(hm: Heightmap) -> GraspCommand:
                action = agent.act(hm.color, hm.depth, epsilon, peg_mask(hm.depth), rng,
                                   skip_q_if_exploring=True)
                chosen["action"], chosen["hm"] = action, hm
                return action_to_command(action, hm)

            assemble, limit = self.plan()
            record, _, _ = self.runner.run(seed, policy, assemble=assemble, time_limit=limit)
            return record, seed, epsilon, chosen["action"], chosen["hm"]
        if episode not in self.pending:  # first episode of a batch: choose K grasps at once
            total = self.cfg.train.episodes
            batch_end = min(episode - episode % self.k + self.k, total)
            assemble, limit = self.plan()
            for e in range(episode, batch_end):
                seed_e = episode_seed(self.cfg.seed, e)
                eps_e = agent.epsilon(e, self.schedule)
                hm_e = self.runner.observe(seed_e)
                act_e = agent.act(hm_e.color, hm_e.depth, eps_e, peg_mask(hm_e.depth), rng,
                                  skip_q_if_exploring=True)
                task = GraspTask(seed_e, action_to_command(act_e, hm_e), assemble, limit)
                self.pending[e] = (self.collector.submit(task), seed_e, eps_e, act_e, hm_e)
        handle, seed, epsilon, action, hm = self.pending.pop(episode)
        return self.collector.result(handle), seed, epsilon, action, hm

    def close(self) -> None:
        if self.collector is not None:
            self.collector.close()


def _threshold_doc(cfg: ExperimentConfig, state: TrainState) -> dict[str, Any]:
    return {"threshold_s": state.threshold, "n_times": len(state.exploration_times),
            "percentile": cfg.reward.threshold_percentile}


def _reward(cfg: ExperimentConfig, mode: str, state: TrainState, record: EpisodeRecord,
            episode: int, out: Path) -> tuple[float, float, float]:
    """``(r_grasp, r_assembly, threshold)`` of an episode (eq. 5), the threshold the running
    percentile while exploring (written to ``threshold.json`` when it freezes), inf before any
    assembly time is known."""
    exploring = episode < cfg.agent.random_episodes
    time_ok = record.assembly_time if record.success else None
    derived = cfg.reward.threshold_s is None and (exploring or state.threshold is None)
    state.threshold = next_threshold(state.exploration_times, state.threshold, time_ok,
                                     exploring, cfg.reward)
    if derived and (not exploring or episode == cfg.agent.random_episodes - 1):
        write_json(out / "threshold.json", _threshold_doc(cfg, state))
    threshold = state.threshold if state.threshold is not None else math.inf
    # Before any assembly time is known no threshold exists, so no r_AM can be earned.
    r_grasp, r_asm = episode_reward(record.grasp_success, time_ok, state.threshold, mode,
                                    cfg.reward)
    return r_grasp, r_asm, threshold


def config_text(cfg: ExperimentConfig, mode: str) -> str:
    """The run's mode, provenance and resolved configuration as Markdown for TensorBoard's text
    tab (tag ``config``, logged at every start and resume)."""
    from vgs.config import to_dict
    from vgs.jsonsafe import dumps
    from vgs.runfolder.common import provenance

    lines = dumps({"mode": mode, **provenance(), "config": to_dict(cfg)}, indent=2)
    return "\n".join("    " + line for line in lines.splitlines())  # a Markdown code block


class _TrainLog:
    """Where a training run reports: a row of ``episodes.csv`` per episode, TensorBoard scalars,
    the progress bar, and a line per checkpoint when there is no bar."""

    def __init__(self, out: Path, rows: list[str], mode: str, start: int, total: int,
                 progress: bool, position: int) -> None:
        from torch.utils.tensorboard import SummaryWriter

        self.out, self.mode, self.total = out, mode, total
        # (a finished run run again gets no new events file: its folder stays as it is)
        self.writer = (SummaryWriter(str(out / "tensorboard"), purge_step=start)
                       if start < total else None)
        self.csv_file, self.table = open_table(out / "episodes.csv", rows)
        self.bar = tqdm(range(start, total), initial=start, total=total, desc=f"train {mode}",
                        disable=not progress, dynamic_ncols=True, position=position)
        self.recent: list[tuple[bool, float]] = []
        self.recent_walls: list[float] = []

    def episode(self, row: dict[str, Any], record: EpisodeRecord, epsilon: float,
                reward: float, r_asm: float, stats: dict[str, float], monitor: DeltaQMonitor,
                wall: float) -> None:
        episode = row["episode"]
        self.table.writerow(rounded_rows([row])[0])  # times to the ms
        self.csv_file.flush()
        writer = self.writer
        writer.add_scalar("charts/grasp_success", int(record.grasp_success), episode)
        writer.add_scalar("charts/assembly_success", int(record.success), episode)
        if record.success:
            writer.add_scalar("charts/assembly_time_s", record.assembly_time, episode)
            writer.add_scalar("charts/grasp_offset_abs_mm",
                              abs(record.grasp_offset) * 1000.0, episode)
        writer.add_scalar("charts/epsilon", epsilon, episode)
        writer.add_scalar("rewards/reward", reward, episode)
        writer.add_scalar("rewards/r_assembly", r_asm, episode)
        writer.add_scalar("losses/td_loss", stats["loss"], episode)
        writer.add_scalar("losses/delta_q", stats["delta_q"], episode)
        writer.add_scalar("losses/delta_q_window_mean", monitor.mean, episode)
        writer.add_scalar("perf/episode_wall_s", wall, episode)

        self.recent = (self.recent + [(record.grasp_success, record.assembly_time
                                       if record.success else math.nan)])[-50:]
        self.recent_walls = (self.recent_walls + [wall])[-50:]
        times = self._times()
        self.bar.set_postfix(grasp=f"{np.mean([g for g, _ in self.recent]):.2f}",
                             T=f"{np.mean(times):.1f}" if times else "-",
                             eps=f"{epsilon:.2f}", dQ=f"{stats['delta_q']:.3f}",
                             loss=f"{stats['loss']:.3f}", conv=int(monitor.converged))

    def _times(self) -> list[float]:
        return [t for _, t in self.recent if math.isfinite(t)]

    def checkpoint_line(self, episode: int) -> None:
        times = self._times()
        print(f"train {self.mode} {self.out}: checkpoint at episode {episode}/{self.total}; "
              f"last {len(self.recent)}: grasp "
              f"{np.mean([g for g, _ in self.recent]):.2f}, assembly time "
              f"{np.mean(times) if times else math.nan:.1f} s, "
              f"{np.mean(self.recent_walls):.1f} s wall per episode", file=sys.stderr,
              flush=True)

    def close(self) -> None:
        self.csv_file.close()
        if self.writer is not None:
            self.writer.close()
