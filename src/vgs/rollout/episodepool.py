"""The episode pool: runs planned test episodes (:class:`EpisodeTask`) in this process, in
spawned worker processes or in Ray actors, and yields one table row per episode; and training's
parallel episodes (:class:`GraspTask`, the grasp already chosen) on the same workers
(:class:`TrainingPool`), local processes or Ray actors.

A worker (:class:`EpisodeWorker`, one per process or actor) keeps its cell and its policies; an
exception in an episode stops the run (:class:`vgs.errors.EpisodeError`; diverged physics is an
``unstable`` failure row), and an episode whose worker process dies is
tried again alone up to :data:`MAX_ATTEMPTS` times before it becomes a ``worker_lost`` row.
:mod:`vgs.experiments.evaluate` plans the episodes and writes the rows.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import signal
import sys
import time
from collections.abc import Generator, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

import numpy as np

from vgs.assembly.episode import EpisodeRunner, GraspCommand
from vgs.assembly.record import EpisodeRecord
from vgs.config import ExperimentConfig, PegConfig
from vgs.errors import ConfigError, EpisodeError, SimulationError, VGSError
from vgs.rollout.policies import Decision, EvalPolicy, episode_policy, is_run_dir, load_policy
from vgs.runfolder.common import host

MAX_ATTEMPTS = 3
BACKENDS = ("local", "ray")
# The longest a Ray worker may take for one episode before it counts as lost [s] (an episode of
# the paper cell takes under a minute of wall time; Ray itself reports a dead actor sooner).
RAY_WAIT_S = 900.0


@dataclass(frozen=True)
class EpisodeTask:
    """One planned test episode: which policy, which scene (seed) and which peg.

    ``job`` tells :func:`evaluate_many` which evaluation the row belongs to.
    """

    index: int
    seed: int
    peg: PegConfig
    policy: str
    job: int = 0


@dataclass(frozen=True)
class GraspTask:
    """One training episode's physics: the scene (seed), the grasp the learner chose, whether to
    assemble after it and the assembly's time limit (:meth:`EpisodeRunner.run`)."""

    seed: int
    command: GraspCommand
    assemble: bool = True
    time_limit: float | None = None


class EpisodeWorker:
    """Runs test episodes; one per worker process (or Ray actor). Policies are loaded on first
    use and kept.

    Args:
        cfg: Experiment configuration.
    """

    def __init__(self, cfg: ExperimentConfig) -> None:
        self.cfg = cfg
        self.runner = EpisodeRunner(cfg)
        self.policies: dict[str, EvalPolicy] = {}

    def policy(self, spec: str) -> EvalPolicy:
        """The policy of ``spec``; networks go to the GPU when ``train.device`` allows one.

        Torch is imported only for a policy that needs it (a training run, or a user policy that
        imports it), so workers of the heuristic policies start in about a second; where it is
        loaded it runs on one thread.
        """
        if spec not in self.policies:
            device = "cpu"
            if is_run_dir(spec):
                import torch

                if self.cfg.train.device != "cpu" and torch.cuda.is_available():
                    device = "cuda"
            self.policies[spec] = load_policy(spec, self.cfg, device)
            torch_module = sys.modules.get("torch")  # loaded by the policy, if it needs it
            if torch_module is not None:
                torch_module.set_num_threads(1)
        return self.policies[spec]

    def run(self, task: EpisodeTask) -> dict[str, Any]:
        """One episode as a table row; diverged physics is an ``unstable`` failure row.

        Raises:
            EpisodeError: On any other exception inside the episode (a bug is not a result).
        """
        t0 = time.perf_counter()
        chosen: dict[str, Decision] = {}
        rng = np.random.default_rng([task.seed, 2])
        try:
            policy = episode_policy(self.policy(task.policy), rng, chosen)
            record, _, _ = self.runner.run(task.seed, policy, peg=task.peg)
            if record.success and not math.isfinite(record.assembly_time):
                record.success, record.failure_reason = False, "unstable"
        except SimulationError:  # the physics diverged: a recorded failure
            record = _failed_record(task, "unstable")
        except Exception as exc:  # noqa: BLE001 - a bug is not a result: the run stops
            message = " ".join(str(exc).split())[:200]
            raise EpisodeError(f"episode {task.index} (seed {task.seed}) raised "
                               f"{type(exc).__name__}: {message}; the journal keeps the "
                               "episodes finished before it: fix the cause and run the same "
                               "command again") from None
        d = chosen.get("decision")
        decision = ({} if d is None else
                    {"rotation": d.rotation, "row": d.row, "col": d.col, "q_value": d.q_value})
        return task_row(task, record, decision, round(time.perf_counter() - t0, 3))

    def grasp(self, task: GraspTask) -> EpisodeRecord:
        """One training episode with its grasp already chosen (an exception propagates: the
        training run stops and resumes from its checkpoint)."""
        record, _, _ = self.runner.run(task.seed, lambda hm: task.command,
                                       assemble=task.assemble, time_limit=task.time_limit)
        return record


_WORKER: EpisodeWorker | None = None


def _init_process(cfg: ExperimentConfig) -> None:
    global _WORKER
    # Ctrl-C reaches the whole process group: the parent handles it (and stops the pool).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _WORKER = EpisodeWorker(cfg)


def _worker() -> EpisodeWorker:
    if _WORKER is None:
        raise VGSError("episode worker used before its initialisation")
    return _WORKER


def _run_in_process(task: EpisodeTask) -> dict[str, Any]:
    return _worker().run(task)


def _grasp_in_process(task: GraspTask) -> EpisodeRecord:
    return _worker().grasp(task)


def task_row(task: EpisodeTask, record: EpisodeRecord, decision: dict[str, Any],
         wall: float) -> dict[str, Any]:
    """One table row (column vocabulary of :mod:`vgs.columns`): the task's place, the record,
    the policy's decision, the wall time, the host."""
    return {"job": task.job, "index": task.index, **record.to_row(),
            "rotation": decision.get("rotation", -1), "row": decision.get("row", -1),
            "col": decision.get("col", -1), "q_value": decision.get("q_value", math.nan),
            "wall_s": wall, **host()}


def _failed_record(task: EpisodeTask, reason: str) -> EpisodeRecord:
    """The record of an episode that produced none (its worker raised or was lost)."""
    return EpisodeRecord(seed=task.seed, peg_mass=task.peg.mass, peg_length=task.peg.length,
                         failure_reason=reason)


def _lost_row(task: EpisodeTask) -> dict[str, Any]:
    return task_row(task, _failed_record(task, "worker_lost"), {}, math.nan)


def single_blas_thread() -> None:
    """Give the worker processes spawned from now on one OpenBLAS thread (unless the user set
    ``OPENBLAS_NUM_THREADS``). An episode's only large matrix product is the camera's; it
    wakes OpenBLAS's helper thread, which then spins on the other core and competes with the
    other worker (about 5 % of an episode's CPU, ``benchmarks/bench_cell.py``). The golden
    records are identical either way (numpy's small products do not thread)."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _pool_round(cfg: ExperimentConfig, queue: list[EpisodeTask], workers: int
                ) -> Generator[dict[str, Any], None, tuple[list[EpisodeTask], list[EpisodeTask]]]:
    """Run ``queue`` on a fresh pool, yielding rows as they finish, until done or broken.

    Returns (as the generator's value):
        The episodes in flight when a worker died (suspects) and those not yet started.
    """
    ctx = mp.get_context("spawn")
    single_blas_thread()
    queue = list(queue)
    futures: dict[Future[dict[str, Any]], EpisodeTask] = {}
    pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init_process,
                               initargs=(cfg,))
    try:
        while queue or futures:
            while queue and len(futures) < workers:
                task = queue.pop(0)
                futures[pool.submit(_run_in_process, task)] = task
            done, _ = wait(futures, return_when=FIRST_COMPLETED)
            for fut in done:
                try:
                    row = fut.result()
                except BrokenProcessPool:
                    return list(futures.values()), queue
                futures.pop(fut)
                yield row
    except BaseException:  # an episode's error, Ctrl-C, SIGTERM: stop the workers now
        stop_pool(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return [], []


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Terminate a process pool's workers at once (their episodes are abandoned) and wait for
    them, so that nothing is left running when the command ends."""
    pool.shutdown(wait=False, cancel_futures=True)
    processes = list((getattr(pool, "_processes", None) or {}).values())  # the stdlib's own
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=5)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=5)


def run_local(cfg: ExperimentConfig, tasks: list[EpisodeTask],
              workers: int) -> Iterator[dict[str, Any]]:
    """Rows of ``tasks`` (in completion order) from ``workers`` spawned processes.

    ``workers == 1`` runs in this process. When a worker process dies, the pool is rebuilt for
    the episodes not yet started, and each episode that was in flight is tried again alone in a
    one-process pool (so a crash is pinned on the episode that caused it), at most
    :data:`MAX_ATTEMPTS` times in all; then it becomes a ``worker_lost`` row.
    """
    if workers == 1:
        worker = EpisodeWorker(cfg)
        yield from map(worker.run, tasks)
        return
    queue = list(tasks)
    while queue:
        suspects, queue = yield from _pool_round(cfg, queue, workers)
        for task in suspects:
            for _ in range(MAX_ATTEMPTS - 1):
                lost, _ = yield from _pool_round(cfg, [task], 1)
                if not lost:
                    break
            else:
                yield _lost_row(task)


def _start_ray(workers: int, address: str | None) -> tuple[Any, bool]:
    """Ray, initialised (a local instance of ``workers`` CPUs when no address and none is
    running), and whether this call started it.

    Raises:
        ConfigError: ``backend`` if Ray is not installed.
    """
    try:
        import ray
    except ImportError as exc:
        raise ConfigError("backend", "ray is not installed; pip install 'vgs[ray]'") from exc
    import logging

    if ray.is_initialized():
        return ray, False
    kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                              "logging_level": logging.ERROR}
    if address is None:
        kwargs["num_cpus"] = workers
    ray.init(address=address, **kwargs)
    return ray, True


def _ray_actor_class(ray: Any) -> Any:
    """:class:`EpisodeWorker` as a Ray actor of one CPU, restarted and its call retried when
    its process dies."""
    return ray.remote(num_cpus=1, max_restarts=MAX_ATTEMPTS - 1,
                      max_task_retries=MAX_ATTEMPTS - 1)(EpisodeWorker)


def run_ray(cfg: ExperimentConfig, tasks: list[EpisodeTask], workers: int,
            address: str | None = None) -> Iterator[dict[str, Any]]:
    """Rows of ``tasks`` from ``workers`` Ray actors (a local Ray instance when no address).

    Actors are restarted when their process dies and the call is retried (Ray's
    ``max_restarts``/``max_task_retries``); an episode whose actor is lost for good becomes a
    ``worker_lost`` row.

    Raises:
        ConfigError: ``backend`` if Ray is not installed.
    """
    ray, started = _start_ray(workers, address)
    try:
        actor_cls = _ray_actor_class(ray)
        actors = [actor_cls.remote(cfg) for _ in range(min(workers, len(tasks)))]
        queue = list(tasks)
        running: dict[Any, tuple[Any, EpisodeTask]] = {}
        idle = list(actors)
        while queue or running:
            while queue and idle:
                actor, task = idle.pop(), queue.pop(0)
                running[actor.run.remote(task)] = (actor, task)
            done, _ = ray.wait(list(running), num_returns=1, timeout=RAY_WAIT_S)
            if not done:
                raise VGSError(f"no Ray worker finished an episode in {RAY_WAIT_S:.0f} s (a "
                               "worker or node is lost); run the same command again to resume")
            actor, task = running.pop(done[0])
            try:
                yield ray.get(done[0])
                idle.append(actor)
            except ray.exceptions.RayActorError:
                yield _lost_row(task)
                idle.append(actor_cls.remote(cfg))
        for actor in actors:
            ray.kill(actor)
    finally:
        if started:
            ray.shutdown()


class TrainingPool:
    """Training's parallel episodes: ``workers`` :class:`EpisodeWorker` processes (``local``,
    spawned) or Ray actors (``ray``; a local Ray instance when no address), kept for the whole
    run.

    :meth:`submit` starts an episode, :meth:`result` waits for its record; training consumes
    the records in episode order, whatever the backend and whichever worker finishes first, so
    local and Ray training give the same table. A
    worker that dies stops the run (a local pool) or is restarted by Ray and its episode
    run again; what is lost for good raises :class:`vgs.errors.VGSError`, and the run resumes
    from its last checkpoint.

    Args:
        cfg: Experiment configuration.
        workers: Worker processes or actors (``train.parallel_episodes``).
        backend: ``local`` or ``ray``.
        address: Address of a running Ray cluster (``ray``; default: start a local one).

    Raises:
        ConfigError: On an unknown backend, or ``ray`` without Ray installed.
    """

    def __init__(self, cfg: ExperimentConfig, workers: int, backend: str = "local",
                 address: str | None = None) -> None:
        if backend not in BACKENDS:
            raise ConfigError("backend", f"must be one of {BACKENDS}, got {backend!r}")
        self.backend = backend
        self._ray: Any = None
        self._started = False
        self._actors: list[Any] = []
        self._next = 0
        self._pool: ProcessPoolExecutor | None = None
        if backend == "local":
            single_blas_thread()
            self._pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"),
                                             initializer=_init_process, initargs=(cfg,))
        else:
            self._ray, self._started = _start_ray(workers, address)
            actor_cls = _ray_actor_class(self._ray)
            self._actors = [actor_cls.remote(cfg) for _ in range(workers)]

    def submit(self, task: GraspTask) -> Any:
        """Start ``task`` on the next worker (round robin); its handle for :meth:`result`."""
        if self._pool is not None:
            return self._pool.submit(_grasp_in_process, task)
        actor = self._actors[self._next % len(self._actors)]
        self._next += 1
        return actor.grasp.remote(task)

    def result(self, handle: Any) -> EpisodeRecord:
        """The record of a submitted task (waits for it).

        Raises:
            VGSError: If its worker was lost for good.
        """
        if self._pool is not None:
            try:
                return handle.result()
            except BrokenProcessPool as exc:
                raise VGSError(f"a training worker process died ({exc}); start the run "
                               "again to resume from its checkpoint") from None
        try:
            return self._ray.get(handle, timeout=RAY_WAIT_S)
        except self._ray.exceptions.GetTimeoutError:
            raise VGSError(f"a training worker returned no episode in {RAY_WAIT_S:.0f} s (a "
                           "worker or node is lost); start the run again to resume from its "
                           "checkpoint") from None
        except self._ray.exceptions.RayActorError as exc:
            raise VGSError(f"a training worker was lost ({type(exc).__name__}); start the run "
                           "again to resume from its checkpoint") from None

    def run(self, tasks: list[GraspTask]) -> list[EpisodeRecord]:
        """The records of ``tasks``, in their order."""
        return [self.result(h) for h in [self.submit(task) for task in tasks]]

    def close(self) -> None:
        """Stop the workers (and the Ray instance this pool started)."""
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
        if self._ray is not None:
            for actor in self._actors:
                self._ray.kill(actor)
            self._actors = []
            if self._started:
                self._ray.shutdown()
            self._ray = None

    def __enter__(self) -> TrainingPool:
        return self

    def __exit__(self, *exc: object) -> None:
        if exc[0] is not None and self._pool is not None:  # an error or a signal: stop now
            stop_pool(self._pool)
        self.close()
