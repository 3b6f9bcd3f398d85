"""Grasp policies for evaluation, named by a string so that worker processes can rebuild them.

A policy spec is one of

* ``center``: the heuristic grasp at the centre of the visible peg, pads along its axis;
* ``random``: a uniformly random pixel on the peg, the jaws across its perceived axis (the
  position action) or at a uniformly random rotation out of the network's R (the rotation
  action): what the agent does while exploring;
* ``com-oracle``: a grasp at the peg's true centre of mass, pads along its perceived axis:
  ground truth, for analysis only (where a grasp at the centre of mass leads, beside the
  centre heuristic, on the ``com`` conditions);
* a training run folder (``run.json`` and ``checkpoint.pt`` from ``vgs train``): the trained
  evaluation network Q_eva acting greedily, ``argmax_(k,i,j) Q(k, i, j)`` over the peg pixels;
* a policy folder (``run.json``, ``policy.pt`` and ``policy.json``, as ``vgs export-policy RUN
  --out FOLDER`` writes it; what a published run commits): the same greedy policy from the
  final evaluation network alone;
* ``package.module:function``: a user policy; ``function(cfg)`` must return an
  :class:`EvalPolicy`.

Every policy but ``com-oracle`` sees only the heightmap (and, for the random one, a
generator seeded from the episode seed), never the simulator state;
:func:`episode_policy` hands the oracle the peg's true centre of mass
(:class:`vgs.assembly.episode.OracleGrasp`).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from vgs.assembly.episode import GraspCommand, OracleGrasp, Policy, center_policy
from vgs.checkpoint import MAX_CHECKPOINT_BYTES, check_regular
from vgs.config import REFERENCE_POLICIES, ExperimentConfig, NetworkConfig, from_dict
from vgs.errors import ConfigError, CorruptFileError
from vgs.grasping.actions import closing_angle, peg_mask
from vgs.sim.camera import Heightmap

HEURISTICS = REFERENCE_POLICIES  # the policies named by a word
POLICY_FORMAT = "vgs-grasp-q/1"  # policy.json of vgs export-policy
POLICY_WEIGHTS, POLICY_DESCRIPTION = "policy.pt", "policy.json"


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


def pads_heading(angle: float) -> float:
    """World heading of the pads' long side [rad] for jaws closing along
    ``(cos angle, sin angle)`` in (column, row) pixel axes, which are world (x, y): the grasp
    primitive's yaw, perpendicular to the closing direction."""
    return angle - math.pi / 2


def pixel_command(hm: Heightmap, row: int, col: int, angle: float) -> GraspCommand:
    """World grasp of pixel (row, col) closing along ``(cos angle, sin angle)``
    (:func:`pads_heading`)."""
    x, y = hm.pixel_to_world(row, col)
    return GraspCommand(float(x), float(y), float(pads_heading(angle)))


@dataclass
class CenterPolicy:
    """The centre heuristic (:func:`vgs.assembly.episode.center_policy`)."""

    label: str = "center"

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision:
        return Decision(center_policy()(hm))


@dataclass
class ComOraclePolicy:
    """The centre-of-mass oracle: the pads at the peg's true centre of mass ``p_world_com``
    (x, y), along its perceived axis (the centre heuristic's heading). Ground truth, for
    analysis only; :func:`episode_policy` passes ``p_world_com``."""

    label: str = "com-oracle"
    reads_ground_truth: bool = True

    def __call__(self, hm: Heightmap, rng: np.random.Generator,
                 p_world_com: np.ndarray | None = None) -> Decision:
        if p_world_com is None:
            raise ConfigError("policy", "com-oracle reads the peg's true centre of mass: run it "
                                        "through vgs evaluate or vgs demo")
        heading = center_policy()(hm).yaw
        return Decision(GraspCommand(float(p_world_com[0]), float(p_world_com[1]), heading))


@dataclass
class RandomPolicy:
    """A uniformly random peg pixel (and rotation, for the rotation action): the agent's
    exploration draw."""

    network: NetworkConfig
    label: str = "random"

    def __call__(self, hm: Heightmap, rng: np.random.Generator) -> Decision:
        mask = peg_mask(hm.depth)
        if not mask.any():
            mask = np.ones_like(mask)
        rows, cols = np.nonzero(mask)
        pick = int(rng.integers(rows.size))
        position = self.network.action == "position"
        k = 0 if position else int(rng.integers(self.network.num_rotations))
        i, j = int(rows[pick]), int(cols[pick])
        angle = closing_angle(self.network.action, k, self.network.num_rotations, hm.depth)
        return Decision(pixel_command(hm, i, j, angle), rotation=k, row=i, col=j)


def load_trained_agent(run_dir: Path, device: str = "cpu", field: str = "policy"
                       ) -> tuple[ExperimentConfig, dict[str, Any], Any, int]:
    """Configuration, ``run.json``, trained agent and episode count of a ``vgs train`` run, or
    of a policy folder (``run.json``, ``policy.pt``, ``policy.json``) when the folder holds no
    checkpoint.

    The checkpoint is read pickle-free (:mod:`vgs.checkpoint`): a file that is not a vgs
    checkpoint is refused before anything in it is unpickled; ``policy.pt`` is read with
    ``torch.load(..., weights_only=True)``.

    Raises:
        ConfigError: ``field`` if the folder holds neither.
        CorruptFileError: If ``run.json`` cannot be read, or the policy files do not fit it;
            :class:`vgs.errors.CheckpointError` if the checkpoint is refused.
    """
    from vgs.grasping.agent import GraspAgent
    from vgs.runfolder.common import check_belongs, check_table_digest, read_json
    from vgs.runfolder.trainfolder import load_checkpoint
    from vgs.validate import check_config

    meta_path, ckpt = run_dir / "run.json", run_dir / "checkpoint.pt"
    weights = run_dir / POLICY_WEIGHTS
    if not meta_path.exists() or not (ckpt.exists() or weights.exists()):
        raise ConfigError(field, f"{run_dir} holds no training run (run.json and checkpoint.pt) "
                                 f"nor a policy folder (run.json and {POLICY_WEIGHTS})")
    meta = read_json(meta_path)
    try:
        run_cfg = check_config(from_dict(ExperimentConfig, meta["config"]))  # bounds included
    except (KeyError, TypeError, ValueError) as exc:  # ConfigError is a ValueError
        raise CorruptFileError(meta_path, f"records no usable configuration ({exc})") from None
    agent = GraspAgent(run_cfg.network, run_cfg.agent, device=device, seed=run_cfg.seed)
    if ckpt.exists():
        state = load_checkpoint(ckpt, agent, device=device)
        check_belongs(state.run, meta, ckpt, meta_path)  # not another run's weights
        check_table_digest(run_dir / "episodes.csv", ckpt,
                           {"episode": state.episode, "table_sha256": state.table_sha256})
        return run_cfg, meta, agent, state.episode
    return run_cfg, meta, agent, _load_policy_files(run_dir, meta, agent, device)


def finished_as_policy(out: Path, total: int) -> bool:
    """Whether ``out`` holds a finished run kept as its final network alone, the way
    ``scripts/carry.sh`` moves a finished run through git: ``policy.pt`` and ``policy.json``
    (``vgs export-policy RUN --out RUN``), the table and ``convergence.json``, no checkpoint.

    Raises:
        CorruptFileError: If that network was trained for fewer than ``total`` episodes (a
            longer run needs the checkpoint, which such a folder no longer has).
    """
    from vgs.runfolder.common import read_json

    if (out / "checkpoint.pt").exists() or not (out / POLICY_WEIGHTS).exists():
        return False
    desc = out / POLICY_DESCRIPTION
    trained = read_json(desc).get("trained_episodes") if desc.exists() else None
    if not isinstance(trained, int) or not (out / "convergence.json").exists():
        raise CorruptFileError(desc, "is missing or records no trained_episodes, and the folder "
                                     "holds no checkpoint.pt to train on from")
    if trained < total:
        raise CorruptFileError(out / POLICY_WEIGHTS,
                               f"is the final network of a run of {trained} episodes, and the "
                               f"folder holds no checkpoint.pt to train on to {total}; train "
                               "into a new folder")
    return True


def _load_policy_files(folder: Path, meta: dict[str, Any], agent: Any, device: str) -> int:
    """Load ``policy.pt`` into the agent's networks (both: the target network is unused when
    acting); return the trained episodes ``policy.json`` records.

    Raises:
        CorruptFileError: If ``policy.json`` is missing, unreadable or of another run, or the
            weights cannot be read safely or do not fit the network of ``run.json``.
    """
    import pickle

    import torch

    from vgs.runfolder.common import read_json

    desc_path, weights_path = folder / POLICY_DESCRIPTION, folder / POLICY_WEIGHTS
    if not desc_path.exists():
        raise CorruptFileError(desc_path, f"is missing beside {POLICY_WEIGHTS}; write both with "
                                          "vgs export-policy RUN --out FOLDER")
    desc = read_json(desc_path)
    episodes = desc.get("trained_episodes")
    if desc.get("format") != POLICY_FORMAT or not isinstance(episodes, int):
        raise CorruptFileError(desc_path, f"is not a {POLICY_FORMAT} description with "
                                          "trained_episodes")
    for key, mine in (("mode", meta.get("mode")), ("backbone", agent.network_cfg.backbone),
                      ("action", agent.network_cfg.action),
                      ("num_rotations", agent.num_rotations), ("rotate", agent.rotate)):
        if desc.get(key, "rotation" if key == "action" else None) != mine:
            raise CorruptFileError(desc_path, f"describes a network with {key} "
                                              f"{desc.get(key)!r}, run.json one with {mine!r}")
    check_regular(weights_path, MAX_CHECKPOINT_BYTES)  # no symlink, device or FIFO; bounded
    try:
        state = torch.load(weights_path, map_location=device, weights_only=True)
    except (pickle.UnpicklingError, RuntimeError, EOFError, ValueError, TypeError,
            OSError) as exc:
        first = " ".join(str(exc).split())[:160]
        raise CorruptFileError(weights_path, f"holds tensors that cannot be read safely "
                                             f"({first})") from None
    own = agent.eva_net.state_dict()
    needed = {k for k in own if not k.endswith("num_batches_tracked")}
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor)
                                              for v in state.values()):
        raise CorruptFileError(weights_path, "is not a dictionary of tensors")
    wrong = sorted((needed - set(state)) | (set(state) - set(own))) or sorted(
        k for k in needed if tuple(state[k].shape) != tuple(own[k].shape))
    if wrong:
        raise CorruptFileError(weights_path, f"does not fit the network of run.json ("
                                             f"{len(wrong)} tensors differ, first {wrong[0]})")
    try:
        agent.eva_net.load_state_dict(state, strict=False)
    except RuntimeError as exc:
        raise CorruptFileError(weights_path, f"does not fit the network of run.json ({exc})") \
            from None
    return episodes


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


def episode_policy(chooser: EvalPolicy, rng: np.random.Generator,
                   chosen: dict[str, Decision]) -> Policy | OracleGrasp:
    """The grasp chooser :meth:`vgs.assembly.episode.EpisodeRunner.run` takes for an
    evaluation policy; its decision lands in ``chosen["decision"]``. A policy with
    ``reads_ground_truth`` (``com-oracle``) gets the peg's true centre of mass too."""
    if getattr(chooser, "reads_ground_truth", False):
        oracle: Any = chooser

        def choose(hm: Heightmap, p_world_com: np.ndarray) -> GraspCommand:
            chosen["decision"] = oracle(hm, rng, p_world_com)
            return chosen["decision"].command

        return OracleGrasp(choose)

    def policy(hm: Heightmap) -> GraspCommand:
        chosen["decision"] = chooser(hm, rng)
        return chosen["decision"].command

    return policy


def is_run_dir(spec: str) -> bool:
    """Whether ``spec`` names a training run folder or a policy folder (``run.json``)."""
    return (Path(spec) / "run.json").exists()


def load_policy(spec: str, cfg: ExperimentConfig, device: str = "cpu") -> EvalPolicy:
    """Build the policy named by ``spec`` (see the module docstring).

    Raises:
        ConfigError: ``policy`` if the spec names nothing usable.
    """
    if spec == "center":
        return CenterPolicy()
    if spec == "random":
        return RandomPolicy(cfg.network)
    if spec == "com-oracle":
        return ComOraclePolicy()
    if is_run_dir(spec):
        return GreedyPolicy(Path(spec), device)
    if ":" in spec and not Path(spec).exists():
        module_name, _, attr = spec.partition(":")
        if not module_name.strip() or not attr.strip():
            raise ConfigError("policy", f"{spec!r} names no module:function")
        try:
            factory: Callable[[ExperimentConfig], EvalPolicy] = getattr(
                importlib.import_module(module_name), attr)
        except Exception as exc:  # noqa: BLE001 - a user module can raise anything on import
            raise ConfigError("policy", f"cannot import {spec!r} ({type(exc).__name__}: "
                                        f"{' '.join(str(exc).split())[:160]})") from None
        try:
            policy = factory(cfg)
        except Exception as exc:  # noqa: BLE001 - the user's factory failed
            raise ConfigError("policy", f"{spec!r} raised {type(exc).__name__}: "
                                        f"{' '.join(str(exc).split())[:160]}") from None
        if not callable(policy):
            raise ConfigError("policy", f"{spec!r} returned {type(policy).__name__}, not a "
                                        "policy (a callable taking heightmap and generator)")
        return policy
    raise ConfigError("policy", f"{spec!r} is neither {' nor '.join(HEURISTICS)}, a training "
                                "run or policy folder (with run.json) nor module:function")


def policy_digest(spec: str, policy: EvalPolicy, legacy: bool = False) -> str:
    """What identifies a policy in an evaluation's ``meta.json``: for a training run or policy
    folder the SHA-256 of the weights its evaluation network acts with (every tensor's name,
    type, shape and bytes, in name order) with its mode, so that another network under the
    same path text is another policy; for ``center`` and ``random`` their name; for
    ``module:function`` the spec.

    Batch norm's ``num_batches_tracked`` counters are left out: they count training steps and
    take no part in acting (running statistics are used), and ``vgs export-policy`` does not
    keep them, so a training run and its exported final network (how ``scripts/carry.sh``
    moves a finished run) are the same policy. ``legacy=True`` gives the digest written before
    2026-12-07, with the counters, which :mod:`vgs.experiments.evaluate` still accepts.
    """
    agent = getattr(policy, "agent", None)
    if agent is None:
        return f"spec:{spec}"
    import hashlib

    import torch

    h = hashlib.sha256(f"{getattr(policy, 'label', '')}\n".encode())
    for name, tensor in sorted(agent.eva_net.state_dict().items()):
        if not legacy and name.endswith("num_batches_tracked"):
            continue
        t = tensor.detach().cpu().contiguous()
        h.update(f"{name} {t.dtype} {tuple(t.shape)}\n".encode())
        h.update(t.flatten().view(torch.uint8).numpy().tobytes())
    return f"sha256:{h.hexdigest()}"


def policy_label(spec: str) -> str:
    """Short name of a policy spec: the run's mode for a run folder, else the spec."""
    if is_run_dir(spec):
        from vgs.runfolder.common import read_json

        return str(read_json(Path(spec) / "run.json").get("mode"))
    return spec
