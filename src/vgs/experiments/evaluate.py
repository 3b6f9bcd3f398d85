"""Evaluation at scale: one policy, one test condition, N seeded episodes, local or Ray workers.

Episode ``i`` of a run with root seed ``S`` is the test scene ``i`` of the condition
(:func:`vgs.config.conditions.eval_scenes`: its episode seed and its peg, paper 4.2) and the
policy; the policy's own random draws (the ``random`` policy) use
``default_rng([episode seed, 2])``.

So the same seed gives the same table whatever the backend, the worker count and the order in
which workers finish, and two policies evaluated with the same seed meet the same scenes (a
paired comparison). Worker processes run torch on one thread, so network outputs are identical
in every process.

Failures never stop a run: an exception inside an episode becomes a row with
``failure_reason = "error:<type>: <message>"``; a worker process that dies takes its episode
with it, the pool is rebuilt and the episode is tried again, up to
:data:`vgs.rollout.episodepool.MAX_ATTEMPTS` times (then ``failure_reason =
"worker_lost"``); :mod:`vgs.rollout.episodepool` runs the episodes.

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
import os
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pandas as pd
from tqdm import tqdm

from vgs.analysis.stats import summarize
from vgs.assembly.record import EpisodeRecord
from vgs.checkpoint import atomic_write_text, open_append
from vgs.columns import rounded, write_parquet
from vgs.config import CONDITIONS, ExperimentConfig, PegConfig, eval_scenes, to_dict
from vgs.errors import ConfigError, CorruptFileError, RunMismatchError
from vgs.rollout.episodepool import BACKENDS, EpisodeTask, run_local, run_ray, task_row
from vgs.rollout.policies import EvalPolicy, load_policy, policy_digest, policy_label
from vgs.runfolder.common import (
    check_request,
    locked,
    provenance,
    read_json,
    table_digests,
    write_json,
)
from vgs.runfolder.folderkind import claim
from vgs.runfolder.journal import encode_row, read_journal
from vgs.validate import MAX_EPISODES, check_config, check_seed


@dataclass(frozen=True)
class EvalSpec:
    """What to evaluate.

    Attributes:
        policy: Policy spec (:mod:`vgs.rollout.policies`).
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
                or not 1 <= self.episodes <= MAX_EPISODES:
            raise ConfigError("episodes", f"must be an integer in [1, {MAX_EPISODES}], got "
                                          f"{str(self.episodes)[:40]}")
        check_seed("seed", self.seed)




def plan_episodes(cfg: ExperimentConfig, spec: EvalSpec) -> list[EpisodeTask]:
    """The episodes of ``spec`` in index order: the condition's test scenes
    (:func:`vgs.config.conditions.eval_scenes`), each to be run by ``spec.policy``."""
    return [EpisodeTask(s.index, s.seed, s.peg, spec.policy)
            for s in eval_scenes(cfg.cell.peg, cfg.eval, spec.condition, spec.seed, spec.episodes)]


# -- the evaluation run --------------------------------------------------------------------------


def _prepare(cfg: ExperimentConfig, spec: EvalSpec, out: Path,
             policy: EvalPolicy) -> dict[int, dict[str, Any]]:
    """Check the request against ``out/meta.json`` (or write it) and the journal against the
    plan; return the rows already in the journal. Call with ``out`` locked."""
    meta = {"policy": policy_label(spec.policy), "policy_source": spec.policy,
            "policy_trained_episodes": getattr(policy, "trained_episodes", None),
            "policy_digest": policy_digest(spec.policy, policy),
            "condition": spec.condition, "episodes": spec.episodes, "seed": spec.seed,
            "config": to_dict(cfg), "provenance": provenance()}
    meta_path = out / "meta.json"
    if meta_path.exists():
        old = read_json(meta_path)
        # A policy is its weights (digest) and mode, not the path text: a folder recorded with
        # a digest compares digests, one written before compares the source text; a training
        # run that trained on since the rows were written is another policy.
        keys = ["condition", "seed", "policy_digest" if "policy_digest" in old
                else "policy_source"]
        if "policy_trained_episodes" in old:  # (not recorded before 2026-11-22)
            keys.append("policy_trained_episodes")
        if (old.get("policy_digest") != meta["policy_digest"]
                and old.get("policy_digest") == policy_digest(spec.policy, policy, legacy=True)):
            old["policy_digest"] = meta["policy_digest"]  # the same weights, digested as before
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
        atomic_write_text(journal, "".join(encode_row(rows[i]) for i in sorted(rows)))
    return rows


def table_order(columns: list[str]) -> list[str]:
    """``columns`` in the order of an evaluation table: the row's place, the record, the
    decision, the host (rows of journals written by earlier versions may order their keys
    otherwise), any other column last."""
    task = EpisodeTask(0, 0, PegConfig(), "")
    template = ["index", "policy", "condition", "root_seed",
                *task_row(task, EpisodeRecord(0, 0.0, 0.0), {}, 0.0)]
    return ([c for c in dict.fromkeys(template) if c in columns]
            + [c for c in columns if c not in template])


def write_tables(df: pd.DataFrame, out: Path) -> None:
    """``out/episodes.parquet`` (units and descriptions in the fields' metadata) and
    ``out/episodes.csv``, each written whole and renamed into place, times to the ms
    (:func:`vgs.columns.rounded`)."""
    df = rounded(df)
    for name, write in (("episodes.parquet", lambda p: write_parquet(df, p, provenance())),
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
                                      **summarize(df), "tables_sha256": table_digests(out)})
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
        claim(out, "evaluation")
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
            journals = [open_append(out / "journal.jsonl") for _, out in jobs]
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
