"""Evaluation at scale: one policy, one test condition, N seeded episodes, local or Ray workers.

Episode ``i`` of a run with root seed ``S`` is fully determined by ``(S, i)`` and the policy:

* the episode seed (peg pose, hole displacement, sensor noise) is the first word of
  ``numpy.random.SeedSequence([S, i, EVAL_STREAM])`` (the tag keeps test scenes apart from the
  training scenes ``SeedSequence([S, i])`` of a run with the same root seed);
* a child of that sequence draws the peg of the condition (paper 4.2):

  - ``nominal``: the configured peg (30 mm x 100 mm, 0.55 kg);
  - ``mass``: ``m = m0 * U(1 - a, 1 + a)`` with ``a = eval.mass_range`` (0.15);
  - ``length``: ``L = L0 * U(1 - b, 1 + b)`` with ``b = eval.length_range`` (0.15) and the mass
    following the volume, ``m = m0 * L / L0``;

* the policy's own random draws (the ``random`` policy) use ``default_rng([episode seed, 2])``.

So the same seed gives the same table whatever the backend, the worker count and the order in
which workers finish, and two policies evaluated with the same seed meet the same scenes (a
paired comparison). Worker processes run torch on one thread, so network outputs are identical
in every process.

Failures never stop a run: an exception inside an episode becomes a row with
``failure_reason = "error:<type>: <message>"``; a worker process that dies takes its episode
with it, the pool is rebuilt and the episode is tried again, up to :data:`MAX_ATTEMPTS` times
(then ``failure_reason = "worker_lost"``).

Resume: every finished row is appended to ``journal.jsonl`` at once; started again with the same
``--out`` the run compares the request with ``meta.json`` (policy, condition, seed,
configuration; only a larger number of episodes is accepted), checks every journal row against
the planned episode of its index (episode seed, peg mass and length), and skips the episodes
already there. A line cut short by a kill (the last one, without its newline) is dropped and its
episode runs again; a duplicate, a row of another plan or an unreadable line is refused, naming
the file and line. The folder is locked while the run works; ``meta.json`` is written
atomically. At the end ``episodes.parquet``, ``episodes.csv`` and ``summary.json`` are written.

Each row records the CPU model and the MuJoCo version of the host that ran it
(``host_cpu``, ``mujoco_version``): the same scene can end differently on another CPU.
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing as mp
import os
import signal
import sys
import time
from collections.abc import Callable, Generator, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from vgs.assembly.episode import EpisodeRunner
from vgs.assembly.record import EpisodeRecord
from vgs.columns import write_parquet
from vgs.config import ExperimentConfig, PegConfig, to_dict
from vgs.errors import ConfigError, CorruptFileError, RunMismatchError, VGSError
from vgs.experiments.journal import encode_row, read_journal
from vgs.experiments.policies import EvalPolicy, is_run_dir, load_policy, policy_label
from vgs.experiments.stats import sample_std
from vgs.runfolder import check_request, host, locked, read_json, write_json
from vgs.validate import check_config, check_seed

CONDITIONS = ("nominal", "mass", "length")
BACKENDS = ("local", "ray")
MAX_ATTEMPTS = 3
EVAL_STREAM = 0xE7A1  # tags the seed sequences of test episodes


@dataclass(frozen=True)
class EvalSpec:
    """What to evaluate.

    Attributes:
        policy: Policy spec (:mod:`vgs.experiments.policies`).
        condition: ``nominal``, ``mass`` or ``length``.
        episodes: Number of test episodes.
        seed: Root seed.
    """

    policy: str
    condition: str
    episodes: int
    seed: int = 0

    def __post_init__(self) -> None:
        if self.condition not in CONDITIONS:
            raise ConfigError("condition", f"must be one of {CONDITIONS}, got {self.condition!r}")
        if isinstance(self.episodes, bool) or not isinstance(self.episodes, int) \
                or self.episodes < 1:
            raise ConfigError("episodes", f"must be an integer >= 1, got {self.episodes!r}")
        check_seed("seed", self.seed)


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


def plan_episodes(cfg: ExperimentConfig, spec: EvalSpec) -> list[EpisodeTask]:
    """The episodes of ``spec`` in index order (module docstring)."""
    tasks = []
    for i in range(spec.episodes):
        seq = np.random.SeedSequence([spec.seed, i, EVAL_STREAM])
        seed = int(seq.generate_state(1)[0])
        rng = np.random.default_rng(seq.spawn(1)[0])
        peg = condition_peg(cfg, spec.condition, float(rng.uniform(-1.0, 1.0)))
        tasks.append(EpisodeTask(i, seed, peg, spec.policy))
    return tasks


def condition_peg(cfg: ExperimentConfig, condition: str, factor: float) -> PegConfig:
    """The peg of a test condition (paper 4.2) for a draw ``factor`` in [-1, 1].

    ``nominal``: the configured peg; ``mass``: its mass times ``1 + eval.mass_range * factor``;
    ``length``: its length times ``1 + eval.length_range * factor``, the mass following.

    Raises:
        ConfigError: ``condition`` if it is not one of :data:`CONDITIONS`.
    """
    nominal = cfg.cell.peg
    if condition == "nominal":
        return nominal
    if condition == "mass":
        return replace(nominal, mass=nominal.mass * (1.0 + cfg.eval.mass_range * factor))
    if condition == "length":
        scale = 1.0 + cfg.eval.length_range * factor
        return replace(nominal, length=nominal.length * scale, mass=nominal.mass * scale)
    raise ConfigError("condition", f"must be one of {CONDITIONS}, got {condition!r}")


# -- one episode, in whatever process runs it ---------------------------------------------------


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
        """One episode as a table row; an exception becomes a failure row."""
        t0 = time.perf_counter()
        decision: dict[str, Any] = {}
        rng = np.random.default_rng([task.seed, 2])
        try:
            chooser = self.policy(task.policy)

            def policy(hm: Any) -> Any:
                d = chooser(hm, rng)
                decision.update(rotation=d.rotation, row=d.row, col=d.col, q_value=d.q_value)
                return d.command

            record, _, _ = self.runner.run(task.seed, policy, peg=task.peg)
            if record.success and not math.isfinite(record.assembly_time):
                record.success, record.failure_reason = False, "unstable"
        except Exception as exc:  # noqa: BLE001 - any failure of one episode is a result row
            record = EpisodeRecord(seed=task.seed, peg_mass=task.peg.mass,
                                   peg_length=task.peg.length)
            message = " ".join(str(exc).split())[:200]
            record.failure_reason = f"error:{type(exc).__name__}: {message}"
        return _row(task, record, decision, round(time.perf_counter() - t0, 3))


_WORKER: EpisodeWorker | None = None


def _init_process(cfg: ExperimentConfig) -> None:
    global _WORKER
    # Ctrl-C reaches the whole process group: the parent handles it (and stops the pool).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _WORKER = EpisodeWorker(cfg)


def _run_in_process(task: EpisodeTask) -> dict[str, Any]:
    if _WORKER is None:
        raise VGSError("evaluation worker used before its initialisation")
    return _WORKER.run(task)


# -- backends ------------------------------------------------------------------------------------


def _row(task: EpisodeTask, record: EpisodeRecord, decision: dict[str, Any],
         wall: float) -> dict[str, Any]:
    """One table row (column vocabulary of :mod:`vgs.columns`): the task's place, the record,
    the policy's decision, the wall time, the host."""
    return {"job": task.job, "index": task.index, **record.to_row(),
            "rotation": decision.get("rotation", -1), "row": decision.get("row", -1),
            "col": decision.get("col", -1), "q_value": decision.get("q_value", math.nan),
            "wall_s": wall, **host()}


def _lost_row(task: EpisodeTask) -> dict[str, Any]:
    record = EpisodeRecord(seed=task.seed, peg_mass=task.peg.mass, peg_length=task.peg.length)
    record.failure_reason = "worker_lost"
    return _row(task, record, {}, math.nan)


def _pool_round(cfg: ExperimentConfig, queue: list[EpisodeTask], workers: int
                ) -> Generator[dict[str, Any], None, tuple[list[EpisodeTask], list[EpisodeTask]]]:
    """Run ``queue`` on a fresh pool, yielding rows as they finish, until done or broken.

    Returns (as the generator's value):
        The episodes in flight when a worker died (suspects) and those not yet started.
    """
    ctx = mp.get_context("spawn")
    queue = list(queue)
    futures: dict[Future[dict[str, Any]], EpisodeTask] = {}
    with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init_process,
                             initargs=(cfg,)) as pool:
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
    return [], []


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


def run_ray(cfg: ExperimentConfig, tasks: list[EpisodeTask], workers: int,
            address: str | None = None) -> Iterator[dict[str, Any]]:
    """Rows of ``tasks`` from ``workers`` Ray actors (a local Ray instance when no address).

    Actors are restarted when their process dies and the call is retried (Ray's
    ``max_restarts``/``max_task_retries``); an episode whose actor is lost for good becomes a
    ``worker_lost`` row.

    Raises:
        ConfigError: ``backend`` if Ray is not installed.
    """
    try:
        import ray
    except ImportError as exc:
        raise ConfigError("backend", "ray is not installed; pip install 'vgs[ray]'") from exc
    import logging

    started = False
    if not ray.is_initialized():
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                  "logging_level": logging.ERROR}
        if address is None:
            kwargs["num_cpus"] = workers
        ray.init(address=address, **kwargs)
        started = True
    try:
        actor_cls = ray.remote(num_cpus=1, max_restarts=MAX_ATTEMPTS - 1,
                               max_task_retries=MAX_ATTEMPTS - 1)(EpisodeWorker)
        actors = [actor_cls.remote(cfg) for _ in range(min(workers, len(tasks)))]
        queue = list(tasks)
        running: dict[Any, tuple[Any, EpisodeTask]] = {}
        idle = list(actors)
        while queue or running:
            while queue and idle:
                actor, task = idle.pop(), queue.pop(0)
                running[actor.run.remote(task)] = (actor, task)
            done, _ = ray.wait(list(running), num_returns=1)
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


# -- the evaluation run --------------------------------------------------------------------------


def summarize(df: pd.DataFrame) -> dict[str, Any]:
    """Success rates and assembly-time statistics of one evaluation table.

    The ``time_*`` statistics are those of the successful assemblies (the paper's measure);
    ``time_per_assembled_s`` is the simulated assembly time of all episodes, failed attempts
    included, divided by the number of pegs assembled.
    """
    ok = df[df["assembly_success"].astype(bool)]
    times = ok["assembly_time_s"].to_numpy(float)

    def stat(fn: Callable[[np.ndarray], Any]) -> float | None:
        return float(fn(times)) if times.size else None

    return {
        "episodes": int(len(df)), "grasp_success_rate": float(df["grasp_success"].mean()),
        "success_rate": float(len(ok) / max(len(df), 1)), "successes": int(len(ok)),
        "time_total_h": float(times.sum() / 3600.0), "time_mean_s": stat(np.mean),
        "time_std_s": stat(lambda t: sample_std(t) if t.size > 1 else 0.0),
        "time_min_s": stat(np.min), "time_max_s": stat(np.max),
        "time_median_s": stat(np.median),
        # Throughput: every assembly attempt's simulated time (a failed one until it was given
        # up; a missed grasp costs none) over the pegs assembled.
        "time_per_assembled_s": float(np.nansum(df["assembly_time_s"].to_numpy(float))
                                      / len(ok))
        if len(ok) else None,
        "abs_grasp_offset_mean_mm": float(np.nanmean(np.abs(df["grasp_offset_mm"])))
        if df["grasp_offset_mm"].notna().any() else None,
        "failure_reasons": {str(k): int(v) for k, v in
                            df.loc[~df["assembly_success"].astype(bool), "failure_reason"]
                            .value_counts().items()},
    }


def _prepare(cfg: ExperimentConfig, spec: EvalSpec, out: Path,
             policy: EvalPolicy) -> dict[int, dict[str, Any]]:
    """Check the request against ``out/meta.json`` (or write it) and the journal against the
    plan; return the rows already in the journal. Call with ``out`` locked."""
    meta = {"policy": policy_label(spec.policy), "policy_source": spec.policy,
            "policy_trained_episodes": getattr(policy, "trained_episodes", None),
            "condition": spec.condition, "episodes": spec.episodes, "seed": spec.seed,
            "config": to_dict(cfg)}
    meta_path = out / "meta.json"
    if meta_path.exists():
        old = read_json(meta_path)
        # A training run that trained on since the rows were written is another policy.
        keys = ["policy_source", "condition", "seed"]
        if "policy_trained_episodes" in old:  # (not recorded before 2026-11-22)
            keys.append("policy_trained_episodes")
        for key in keys:
            if json.dumps(old.get(key)) != json.dumps(meta[key]):
                raise RunMismatchError(key, f"{out} holds another evaluation ({old.get(key)!r}, "
                                            f"not {meta[key]!r}); use a new folder")
        if not isinstance(old.get("config"), dict):
            raise CorruptFileError(meta_path, "records no configuration")
        check_request(old["config"], cfg, meta_path, extendable=("eval.episodes",))
        recorded = old.get("episodes")
        if isinstance(recorded, int) and spec.episodes < recorded:
            raise RunMismatchError("episodes", f"{out} holds an evaluation of {recorded} "
                                               f"episodes, not {spec.episodes}; ask for "
                                               f"{recorded} or more (more extends it), or use a "
                                               "new folder")
    journal = out / "journal.jsonl"
    rows, cut = read_journal(journal, plan_episodes(cfg, spec))
    write_json(meta_path, meta)
    if cut:  # drop the line torn by a kill, so that appending starts on a new line
        tmp = journal.with_name(f".{journal.name}.tmp")
        tmp.write_text("".join(encode_row(rows[i]) for i in sorted(rows)))
        os.replace(tmp, journal)
    return rows


def table_order(columns: list[str]) -> list[str]:
    """``columns`` in the order of an evaluation table: the row's place, the record, the
    decision, the host (rows of journals written by earlier versions may order their keys
    otherwise), any other column last."""
    task = EpisodeTask(0, 0, PegConfig(), "")
    template = ["index", "policy", "condition", "root_seed",
                *_row(task, EpisodeRecord(0, 0.0, 0.0), {}, 0.0)]
    return ([c for c in dict.fromkeys(template) if c in columns]
            + [c for c in columns if c not in template])


def write_tables(df: pd.DataFrame, out: Path) -> None:
    """``out/episodes.parquet`` (units and descriptions in the fields' metadata) and
    ``out/episodes.csv``, each written whole and renamed into place."""
    for name, write in (("episodes.parquet", lambda p: write_parquet(df, p)),
                        ("episodes.csv", lambda p: df.to_csv(p, index=False))):
        tmp = out / f".{name}.tmp"
        write(tmp)
        os.replace(tmp, out / name)


def _finish(spec: EvalSpec, out: Path, rows: dict[int, dict[str, Any]]) -> pd.DataFrame:
    label = policy_label(spec.policy)
    df = pd.DataFrame([rows[i] for i in range(spec.episodes)]).drop(columns="job")
    df.insert(1, "policy", label)
    df.insert(2, "condition", spec.condition)
    df.insert(3, "root_seed", spec.seed)
    df = df[table_order(list(df.columns))]
    # summary.json, which marks the evaluation finished, comes last.
    write_tables(df, out)
    write_json(out / "summary.json", {"policy": label, "condition": spec.condition,
                                      **summarize(df)})
    return df


def evaluate_many(cfg: ExperimentConfig, jobs: list[tuple[EvalSpec, Path]],
                  workers: int | None = None, backend: str = "local",
                  ray_address: str | None = None, progress: bool = True) -> list[pd.DataFrame]:
    """Run (or resume) several evaluations on one set of workers.

    One pool (or set of Ray actors) serves every job, so process start-up, imports and cell
    compilation are paid once. Each job writes its own folder (see :func:`evaluate`).

    Returns:
        One table per job, rows in index order.

    Raises:
        ConfigError: On a bad backend, worker count, configuration or policy (checked before
            anything is written).
        RunMismatchError: If a folder holds another evaluation.
        CorruptFileError: If a folder's ``meta.json`` or journal cannot be read or holds rows
            of another plan.
        FolderBusyError: If another process is working in one of the folders.
    """
    if backend not in BACKENDS:
        raise ConfigError("backend", f"must be one of {BACKENDS}, got {backend!r}")
    workers = (os.cpu_count() or 1) if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError("workers", f"must be an integer >= 1, got {workers!r}")
    cfg = check_config(cfg)  # before anything is written
    for _, out in jobs:
        if out.exists() and not out.is_dir():
            raise ConfigError("out", f"{out} is a file, not a folder")
    # Fail here, not in every worker, on a bad spec or a refused checkpoint.
    policies = {spec.policy: load_policy(spec.policy, cfg) for spec, _ in jobs}
    with contextlib.ExitStack() as stack:
        for _, out in jobs:
            stack.enter_context(locked(out))
        done = [_prepare(cfg, spec, out, policies[spec.policy]) for spec, out in jobs]
        return _evaluate_locked(cfg, jobs, done, workers, backend, ray_address, progress)


def _evaluate_locked(cfg: ExperimentConfig, jobs: list[tuple[EvalSpec, Path]],
                     done: list[dict[int, dict[str, Any]]], workers: int, backend: str,
                     ray_address: str | None, progress: bool) -> list[pd.DataFrame]:
    tasks = [replace(t, job=j) for j, (spec, _) in enumerate(jobs)
             for t in plan_episodes(cfg, spec) if t.index not in done[j]]
    total = sum(spec.episodes for spec, _ in jobs)
    desc = (f"eval {policy_label(jobs[0][0].policy)}/{jobs[0][0].condition}" if len(jobs) == 1
            else f"eval {len(jobs)} jobs")
    log_every = max(1, total // 20)  # with progress off: a line per 5 % for unattended logs
    bar = tqdm(total=total, initial=total - len(tasks), unit="episode", desc=desc,
               disable=not progress, dynamic_ncols=True)
    with bar:
        if tasks:
            n = min(workers, len(tasks))
            source = (run_local(cfg, tasks, n) if backend == "local"
                      else run_ray(cfg, tasks, n, ray_address))
            journals = [(out / "journal.jsonl").open("a") for _, out in jobs]
            try:
                finished = ok = 0
                for row in source:
                    job = int(row["job"])
                    done[job][int(row["index"])] = row
                    journals[job].write(encode_row(row))
                    journals[job].flush()
                    bar.update(1)
                    finished, ok = finished + 1, ok + int(bool(row["assembly_success"]))
                    bar.set_postfix(success=f"{ok / finished:.2f}")
                    if not progress and (finished % log_every == 0 or finished == len(tasks)):
                        print(f"{desc}: {total - len(tasks) + finished}/{total} episodes, "
                              f"assembled {ok}/{finished} this run", file=sys.stderr,
                              flush=True)
            finally:
                for fh in journals:
                    fh.close()
    return [_finish(spec, out, done[j]) for j, (spec, out) in enumerate(jobs)]


def evaluate(cfg: ExperimentConfig, spec: EvalSpec, out: Path, workers: int | None = None,
             backend: str = "local", ray_address: str | None = None,
             progress: bool = True) -> pd.DataFrame:
    """Run (or resume) an evaluation; write ``episodes.parquet``/``.csv`` and ``summary.json``.

    Args:
        cfg: Experiment configuration (cell, controller, assembly, ``eval`` ranges).
        spec: Policy, condition, number of episodes, root seed.
        out: Output folder; a folder holding a different evaluation is refused.
        workers: Parallel workers (default: the number of CPU cores).
        backend: ``local`` (processes) or ``ray``.
        ray_address: Address of a running Ray cluster (``ray`` backend; default: start one).
        progress: Show a progress bar.

    Returns:
        The table, one row per episode in index order.

    Raises:
        ConfigError: On a bad backend, worker count or policy, or a folder of another run.
    """
    return evaluate_many(cfg, [(spec, out)], workers, backend, ray_address, progress)[0]
