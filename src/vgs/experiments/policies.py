"""Grasp policies for evaluation, named by a string so that worker processes can rebuild them.

A policy spec is one of

* ``center``: the heuristic grasp at the centre of the visible peg, pads along its axis;
* ``random``: a uniformly random pixel on the peg and a uniformly random rotation out of the
  network's R (what the agent does while exploring);
* a training run folder (``run.json`` and ``checkpoint.pt`` from ``vgs train``): the trained
  evaluation network Q_eva acting greedily, ``argmax_(k,i,j) Q(k, i, j)`` over the peg pixels;
* ``package.module:function``: a user policy; ``function(cfg)`` must return an
  :class:`EvalPolicy`.

Every policy sees only the heightmap (and, for the random one, a generator seeded from the
episode seed), never the simulator state.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from vgs.assembly.episode import GraspCommand, center_policy
from vgs.config import ExperimentConfig, from_dict
from vgs.errors import ConfigError, CorruptFileError
from vgs.grasping.actions import peg_mask, rotation_angle
from vgs.sim.camera import Heightmap

HEURISTICS = ("center", "random")


@dataclass
class Decision:
    """A grasp and what the policy knows about it (NaN/-1 where it does not apply)."""

    command: GraspCommand
    rotation: int = -1
    row: int = -1
    col: int = -1
    q_value: float = math.nan
    extra: dict[str, Any] = field(default_factory=dict)


class EvalPolicy(Protocol):
    """Chooses a grasp from the heightmap; ``rng`` is seeded from the episode seed."""

    label: str

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision: ...


def pixel_command(hm: Heightmap, row: int, col: int, angle: float) -> GraspCommand:
    """World grasp of pixel (row, col) closing along ``(cos angle, sin angle)``.

    The closing direction is expressed in (column, row) pixel axes, which are world (x, y); the
    grasp primitive takes the heading of the pads' long side, perpendicular to it.
    """
    x, y = hm.pixel_to_world(row, col)
    return GraspCommand(float(x), float(y), float(angle - math.pi / 2))


@dataclass
class CenterPolicy:
    """The centre heuristic (:func:`vgs.assembly.episode.center_policy`)."""

    label: str = "center"

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision:
        return Decision(center_policy()(hm))


@dataclass
class RandomPolicy:
    """A uniformly random peg pixel and rotation (the agent's exploration draw)."""

    num_rotations: int
    label: str = "random"

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision:
        mask = peg_mask(hm.depth)
        if not mask.any():
            mask = np.ones_like(mask)
        rows, cols = np.nonzero(mask)
        pick = int(rng.integers(rows.size))
        k = int(rng.integers(self.num_rotations))
        i, j = int(rows[pick]), int(cols[pick])
        angle = rotation_angle(k, self.num_rotations)
        return Decision(pixel_command(hm, i, j, angle), rotation=k, row=i, col=j)


def load_trained_agent(run_dir: Path, device: str = "cpu", field: str = "policy"
                       ) -> tuple[ExperimentConfig, dict[str, Any], Any, int]:
    """Configuration, ``run.json``, trained agent and episode count of a ``vgs train`` run.

    The checkpoint is read pickle-free (:mod:`vgs.checkpoint`): a file that is not a vgs
    checkpoint is refused before anything in it is unpickled.

    Raises:
        ConfigError: ``field`` if the folder holds no run (``run.json`` and ``checkpoint.pt``).
        CorruptFileError: If ``run.json`` cannot be read;
            :class:`vgs.errors.CheckpointError` if the checkpoint is refused.
    """
    from vgs.experiments.train import load_checkpoint
    from vgs.grasping.agent import GraspAgent
    from vgs.runfolder import read_json

    meta_path, ckpt = run_dir / "run.json", run_dir / "checkpoint.pt"
    if not meta_path.exists() or not ckpt.exists():
        raise ConfigError(field, f"{run_dir} holds no training run (run.json and checkpoint.pt)")
    meta = read_json(meta_path)
    try:
        run_cfg = from_dict(ExperimentConfig, meta["config"])
    except (KeyError, TypeError, ValueError) as exc:
        raise CorruptFileError(meta_path, f"records no usable configuration ({exc})") from None
    agent = GraspAgent(run_cfg.network, run_cfg.agent, device=device, seed=run_cfg.seed)
    state = load_checkpoint(ckpt, agent, device=device)
    return run_cfg, meta, agent, state.episode


class GreedyPolicy:
    """A trained run's evaluation network acting greedily on the peg pixels.

    Args:
        run_dir: Folder of a ``vgs train`` run.
        device: Torch device.

    Raises:
        ConfigError: If the folder holds no run.
    """

    def __init__(self, run_dir: Path, device: str = "cpu") -> None:
        self.run_config, meta, self.agent, self.trained_episodes = load_trained_agent(
            run_dir, device)
        self.label = str(meta["mode"])

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision:
        action = self.agent.act(hm.color, hm.depth, 0.0, peg_mask(hm.depth), rng)
        return Decision(pixel_command(hm, action.row, action.col, action.angle),
                        rotation=action.rotation, row=action.row, col=action.col,
                        q_value=action.q_value)


def is_run_dir(spec: str) -> bool:
    """Whether ``spec`` names a training run folder."""
    return (Path(spec) / "run.json").exists()


def load_policy(spec: str, cfg: ExperimentConfig, device: str = "cpu") -> EvalPolicy:
    """Build the policy named by ``spec`` (see the module docstring).

    Raises:
        ConfigError: ``policy`` if the spec names nothing usable.
    """
    if spec == "center":
        return CenterPolicy()
    if spec == "random":
        return RandomPolicy(cfg.network.num_rotations)
    if is_run_dir(spec):
        return GreedyPolicy(Path(spec), device)
    if ":" in spec and not Path(spec).exists():
        module_name, _, attr = spec.partition(":")
        try:
            factory: Callable[[ExperimentConfig], EvalPolicy] = getattr(
                importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as exc:
            raise ConfigError("policy", f"cannot import {spec!r} ({exc})") from exc
        return factory(cfg)
    raise ConfigError("policy", f"{spec!r} is neither {' nor '.join(HEURISTICS)}, a training "
                                "run folder (with run.json) nor module:function")


def policy_label(spec: str) -> str:
    """Short name of a policy spec: the run's mode for a run folder, else the spec."""
    if is_run_dir(spec):
        from vgs.runfolder import read_json

        return str(read_json(Path(spec) / "run.json").get("mode"))
    return spec
