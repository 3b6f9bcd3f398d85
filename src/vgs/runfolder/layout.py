"""Where a reproduction folder keeps each stage's results (torch-free, shared by ``reproduce``,
``status``, the report and ``--publish``).

::

    DIR/reproduce.json                          profile, configuration, machine, stage walls
    DIR/train/<mode>_s<seed>/                   one training run (``vgs train --out``)
    DIR/eval/<mode>/s<seed>/<condition>/        a trained policy on one condition
    DIR/eval/<reference>/s0/<condition>/        a reference heuristic (``center``, ``random``)
    DIR/eval/<label>/<condition>/               all training seeds of one label, merged
    DIR/sweep/                                  the grasp-position sweep
    DIR/report.md, DIR/report.html              the report
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from vgs.config import ExperimentConfig
from vgs.grasping.rewards import MODES


@dataclass(frozen=True)
class TrainRun:
    """One training run of a reproduction.

    Attributes:
        mode: ``baseline`` or ``vgs``.
        seed: Root seed of the run.
        folder: ``DIR/train/<mode>_s<seed>``.
    """

    mode: str
    seed: int
    folder: Path


@dataclass(frozen=True)
class EvalJob:
    """One evaluation of a reproduction: a policy on a condition.

    Attributes:
        label: Policy label in the report (``baseline``, ``vgs``, ``center`` ...).
        policy: Policy spec for :func:`vgs.rollout.policies.load_policy` (a run folder or
            a heuristic's name).
        condition: ``nominal``, ``mass`` or ``length``.
        folder: ``DIR/eval/<label>/s<seed>/<condition>``.
    """

    label: str
    policy: str
    condition: str
    folder: Path


def train_runs(cfg: ExperimentConfig, out: Path) -> list[TrainRun]:
    """Every training run of the reproduction in ``out``: each seed, baseline then VGS."""
    return [TrainRun(mode, seed, out / "train" / f"{mode}_s{seed}")
            for seed in cfg.reproduce.train_seeds for mode in MODES]


def eval_jobs(cfg: ExperimentConfig, out: Path) -> list[EvalJob]:
    """Every evaluation of the reproduction in ``out``, condition by condition: the trained
    runs, then the reference policies."""
    policies = [(run.mode, str(run.folder), out / "eval" / run.mode / f"s{run.seed}")
                for run in train_runs(cfg, out)]
    policies += [(ref, ref, out / "eval" / ref / "s0") for ref in cfg.reproduce.reference_policies]
    return [EvalJob(label, spec, condition, folder / condition)
            for condition in cfg.reproduce.conditions for label, spec, folder in policies]


def train_folders(out: Path) -> list[Path]:
    """The training-run folders found in ``out/train``, sorted, whatever the configuration (the
    report and ``--publish`` read a folder as they find it)."""
    return sorted((out / "train").glob("*"))


def holds_network(run: Path) -> bool:
    """Whether a training-run folder holds its network: ``checkpoint.pt``, or ``policy.pt``
    alone when a finished run was kept as its final network (``scripts/carry.sh``)."""
    return (run / "checkpoint.pt").exists() or (run / "policy.pt").exists()


def eval_tables(out: Path) -> list[Path]:
    """The merged evaluation tables found in ``out``, sorted:
    ``DIR/eval/<label>/<condition>/episodes.parquet``."""
    return sorted((out / "eval").glob("*/*/episodes.parquet"))
