"""``vgs reproduce``: the paper's comparison with one command, resumable stage by stage.

Stages, each resumable on its own (run the same command again to continue):

1. **train**: for every seed of ``reproduce.train_seeds`` the baseline and VGS
   (``DIR/train/<mode>_s<seed>``, checkpoints every ``train.checkpoint_every`` episodes). With
   two or more workers the runs go side by side in separate processes, each with an equal share
   of the CPU threads.
2. **evaluate**: every trained run, greedily, and the reference policies, on every condition
   (``DIR/eval/<policy>/<condition>``, ``eval.episodes`` test episodes each, root seed
   ``reproduce.eval_seed``: all policies meet the same scenes). Runs of several training seeds
   are evaluated one after the other and their tables concatenated.
3. **sweep**: the grasp-position sweep (``DIR/sweep``), ``reproduce.sweep_offsets`` offsets x
   ``reproduce.sweep_trials`` trials, nominal peg.
4. **report**: :func:`vgs.analysis.report.build_report`.

``DIR/reproduce.json`` holds the profile, the configuration, the machine and the wall time of
each stage; it is written atomically. A folder made with another configuration is refused,
naming the first field that differs; only ``eval.episodes`` may grow (more tests: the journals'
rows are kept and the extra episodes run). Each stage holds the folder's lock
(:func:`vgs.runfolder.common.locked`), so a second ``vgs reproduce`` in the same folder is refused.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import platform
import shlex
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

from vgs.analysis.report import build_report
from vgs.analysis.stats import summarize
from vgs.config import ExperimentConfig, to_dict
from vgs.errors import ConfigError, CorruptFileError
from vgs.experiments.evaluate import EvalSpec, evaluate_many, write_tables
from vgs.experiments.train import train
from vgs.runfolder.common import (
    check_belongs,
    check_request,
    check_table_digest,
    locked,
    provenance,
    read_json,
    read_table,
    table_digests,
    write_json,
)
from vgs.runfolder.folderkind import claim
from vgs.runfolder.layout import eval_jobs, train_runs
from vgs.runfolder.trainfolder import git_revision
from vgs.validate import check_config


def machine() -> str:
    """One line describing the machine (CPU cores, GPU if any)."""
    import torch

    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "no GPU"
    return (f"{platform.node()} ({platform.machine()}, {os.cpu_count()} CPU cores, {gpu}, "
            f"Python {platform.python_version()}, torch {torch.__version__})")


def _ignore_sigint() -> None:
    """Ctrl-C reaches the whole process group: the parent handles it (and stops the pool)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _train_job(args: tuple[ExperimentConfig, str, str, bool, int, int, str, str | None]
               ) -> str:
    cfg, mode, out, progress, threads, position, backend, ray_address = args
    return str(train(cfg, mode, Path(out), progress=progress, threads=threads,
                     position=position, backend=backend, ray_address=ray_address))


class Reproduction:
    """One reproduction folder.

    Args:
        cfg: Experiment configuration (a profile with overrides).
        out: Output folder.
        workers: Parallel processes (default: the number of CPU cores).
        backend: ``local`` or ``ray`` for the evaluations and the training runs' parallel
            episodes (``train.parallel_episodes`` > 1; without ``ray_address`` each training
            run starts its own local Ray instance).
        ray_address: Ray cluster address (default: a local one).
        progress: Show progress bars.

    Raises:
        ConfigError: If ``out`` holds a reproduction with another configuration.
    """

    def __init__(self, cfg: ExperimentConfig, out: Path, workers: int | None = None,
                 backend: str = "local", ray_address: str | None = None,
                 progress: bool = True) -> None:
        cfg = check_config(cfg)  # before anything is written
        self.cfg = cfg
        self.out = out
        self.workers = (os.cpu_count() or 1) if workers is None else workers
        if isinstance(self.workers, bool) or not isinstance(self.workers, int) \
                or self.workers < 1:
            raise ConfigError("workers", f"must be an integer >= 1, got {self.workers!r}")
        if out.exists() and not out.is_dir():
            raise ConfigError("out", f"{out} is a file, not a folder")
        claim(out, "reproduction")
        self.backend = backend
        self.ray_address = ray_address
        self.progress = progress
        self.meta_path = out / "reproduce.json"
        self.meta: dict[str, Any] = {}
        with self.locked():
            if self.meta_path.exists():
                self.meta = read_json(self.meta_path)
                if not isinstance(self.meta.get("config"), dict):
                    raise CorruptFileError(self.meta_path, "records no configuration")
                check_request(self.meta["config"], cfg, self.meta_path,
                              extendable=("eval.episodes",))
            self.meta.update({"profile": cfg.name, "config": to_dict(cfg),
                              "machine": machine(), "git_revision": git_revision(),
                              "provenance": provenance(),
                              "command": "vgs " + shlex.join(sys.argv[1:])
                              if sys.argv and sys.argv[0].endswith("vgs") else None})
            self.meta.setdefault("stage_wall_s", {})
            self._save()

    def locked(self) -> Any:
        """The folder's lock (:func:`vgs.runfolder.common.locked`), held by every stage."""
        return locked(self.out)

    def _save(self) -> None:
        write_json(self.meta_path, self.meta)

    def _stage(self, name: str, t0: float) -> None:
        walls = self.meta["stage_wall_s"]
        walls[name] = walls.get(name, 0.0) + time.perf_counter() - t0
        self._save()

    def run_dirs(self) -> list[tuple[str, int, Path]]:
        """(mode, seed, folder) of every training run."""
        return [(run.mode, run.seed, run.folder) for run in train_runs(self.cfg, self.out)]

    def _train_unlocked(self) -> None:
        """Stage 1: train (or resume) every run; runs go side by side over the workers."""
        t0 = time.perf_counter()
        todo = [run for run in self.run_dirs() if not self._trained(run[2])]
        # The runs left share the cores (a lone run left, e.g. VGS after the baseline, has
        # them all for its network's threads).
        parallel = max(1, min(self.workers, len(todo)))
        threads = max(1, (os.cpu_count() or 1) // parallel)
        jobs = [(replace(self.cfg, seed=seed), mode, str(folder), self.progress, threads,
                 i % parallel, self.backend, self.ray_address)
                for i, (mode, seed, folder) in enumerate(todo)]
        if parallel == 1:
            for job in jobs:
                _train_job(job)
        else:
            with ProcessPoolExecutor(parallel, mp_context=mp.get_context("spawn"),
                                     initializer=_ignore_sigint) as pool:
                list(pool.map(_train_job, jobs))
        self._stage("train", t0)

    def _trained(self, folder: Path) -> bool:
        """Whether the training run in ``folder`` has finished; a finished one must be the run
        this reproduction's slot asks for (:meth:`_check_slot`)."""
        table = folder / "episodes.csv"
        if not table.exists() or not (folder / "convergence.json").exists():
            return False
        self._check_slot(folder)
        return len(read_table(table, "train")) >= self.cfg.train.episodes

    def _check_slot(self, folder: Path) -> None:
        """The finished run in ``folder`` against its slot: ``run.json`` of the slot's mode and
        of this reproduction's configuration with the slot's seed, its checkpoint that run's
        (:func:`vgs.runfolder.common.check_belongs`), its table the rows the checkpoint saw.

        Raises:
            RunMismatchError: Naming the first field that differs.
            CorruptFileError: If a file is damaged or belongs to another run.
        """
        from vgs.checkpoint import read_meta
        from vgs.errors import RunMismatchError

        slot = next(run for run in train_runs(self.cfg, self.out) if run.folder == folder)
        meta_path = folder / "run.json"
        if not meta_path.exists():
            raise CorruptFileError(meta_path, "is missing beside a finished table; restore it")
        meta = read_json(meta_path)
        if meta["mode"] != slot.mode:
            raise RunMismatchError("mode", f"{folder} holds a {meta['mode']} run, not the "
                                           f"{slot.mode} run of this slot")
        check_request(meta["config"], replace(self.cfg, seed=slot.seed), meta_path,
                      extendable=("eval.episodes",))
        ckpt = folder / "checkpoint.pt"
        if ckpt.exists():
            saved = read_meta(ckpt)
            check_belongs(saved.get("run"), meta, ckpt, meta_path)
            check_table_digest(folder / "episodes.csv", ckpt, saved)

    def _evaluate_unlocked(self) -> None:
        """Stage 2: every policy on every condition.

        Raises:
            ConfigError: ``stages`` if a training run has not finished (its greedy policy would
                be evaluated half-trained, and the rows kept on resume).
        """
        t0 = time.perf_counter()
        r = self.cfg.reproduce
        unfinished = [folder.name for _, _, folder in self.run_dirs() if not self._trained(folder)]
        if unfinished:
            raise ConfigError("stages", f"training has not finished in {', '.join(unfinished)}; "
                                        "run the train stage first")
        layout = eval_jobs(self.cfg, self.out)
        jobs = [(EvalSpec(job.policy, job.condition, self.cfg.eval.episodes, r.eval_seed),
                 job.folder) for job in layout]
        evaluate_many(self.cfg, jobs, workers=self.workers, backend=self.backend,
                      ray_address=self.ray_address, progress=self.progress)
        for condition in r.conditions:
            for label in dict.fromkeys(job.label for job in layout):
                self._merge(label, condition)
        self._stage("evaluate", t0)

    def _merge(self, label: str, condition: str) -> None:
        """``eval/<label>/<condition>/episodes.parquet``: the tables of all training seeds."""
        parts = sorted((self.out / "eval" / label).glob(f"s*/{condition}/episodes.parquet"))
        df = pd.concat([read_table(p, "eval").assign(train_run=p.parent.parent.name)
                        for p in parts], ignore_index=True)
        if len(parts) > 1:  # several training seeds: keep the index unique per seed
            df["index"] = range(len(df))
        dest = self.out / "eval" / label / condition
        dest.mkdir(parents=True, exist_ok=True)
        write_tables(df, dest)
        write_json(dest / "summary.json", {"policy": label, "condition": condition,
                                           "tables_sha256": table_digests(dest),
                                           **summarize(df)})

    def _sweep_unlocked(self) -> None:
        """Stage 3: the grasp-position sweep (skipped when done or disabled)."""
        r = self.cfg.reproduce
        folder = self.out / "sweep"
        if r.sweep_offsets == 0 or (folder / "summary.json").exists():
            return
        from vgs.experiments.sweep import SweepSpec, default_offsets, sweep_to_folder

        t0 = time.perf_counter()
        spec = SweepSpec(default_offsets(self.cfg.cell.peg, r.sweep_offsets), r.sweep_trials,
                         seed=r.eval_seed)
        sweep_to_folder(self.cfg, spec, folder, workers=self.workers, progress=self.progress)
        self._stage("sweep", t0)

    def _report_unlocked(self) -> Path:
        """Stage 4: the report."""
        t0 = time.perf_counter()
        self.meta["finished"] = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
        self._save()
        path = build_report(self.out)  # titled with the profile of reproduce.json
        self._stage("report", t0)
        return path

    def train(self) -> None:
        """Stage 1 (:meth:`_train_unlocked`) with the folder locked."""
        with self.locked():
            self._train_unlocked()

    def evaluate(self) -> None:
        """Stage 2 (:meth:`_evaluate_unlocked`) with the folder locked."""
        with self.locked():
            self._evaluate_unlocked()

    def sweep(self) -> None:
        """Stage 3 (:meth:`_sweep_unlocked`) with the folder locked."""
        with self.locked():
            self._sweep_unlocked()

    def report(self) -> Path:
        """Stage 4 (:meth:`_report_unlocked`) with the folder locked."""
        with self.locked():
            return self._report_unlocked()

    def run(self) -> Path:
        """All stages; returns the report's path."""
        self.train()
        self.evaluate()
        self.sweep()
        return self.report()
