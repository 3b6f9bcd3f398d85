"""Configuration of grasp learning: network, agent, reward, training."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vgs.config.checks import check_fraction, check_non_negative, check_positive
from vgs.errors import ConfigError

BACKBONES = ("densenet121", "light")
ACTIONS = ("position", "rotation")
ROTATE_MODES = ("input", "features", "none")
PRECISIONS = ("float32", "bfloat16")


@dataclass(frozen=True)
class NetworkConfig:
    """Fully convolutional grasp Q network (paper 3.1).

    Attributes:
        action: ``position`` (the paper's action: a pixel of one H x W Q map; the jaws close
            across the peg's axis as perceived in the same heightmap,
            :func:`vgs.grasping.actions.perceived_jaw_angle`) or ``rotation`` (the action space
            of visual-pushing-grasping, which the paper does not mention: a pixel and one of R
            jaw angles, R Q maps; the policy learns the jaw angle as well).
        backbone: ``densenet121`` (paper) or ``light`` (fast CPU runs).
        num_rotations: Number of grasp orientations R over 360 degrees, theta_k = 2 pi k / R
            (k and k + R/2 are the same two-finger grasp); the ``rotation`` action only.
        weights: Optional path of a local weights file for the trunks.
        rotate: How the network sees the jaw angle. ``position`` action: ``input`` (the
            heightmap turned once into the jaws' frame by the perceived angle before the
            trunks) or ``none`` (the heightmap as captured). ``rotation`` action: ``input``
            (the heightmap turned R times before the trunks, as VPG does) or ``features``
            (trunks run once, the head conditioned on the angle; faster, not in VPG, and it
            did not learn the jaw angle: docs/training.md).
        depth_mean: Mean subtracted from the depth heightmap [m].
        depth_std: Scale dividing the depth heightmap [m].
        precision: ``float32`` (default) or ``bfloat16``: the forward passes (decisions, TD
            targets, updates) under ``torch.autocast`` in bfloat16, weights, optimiser and loss
            in float32. About 3x faster DenseNet-121 decisions on a CPU with AMX or
            AVX512-BF16 (docs/grasping.md); Q values agree with float32 within bfloat16
            rounding. A compute setting, not part of the architecture: a checkpoint loads
            under either.
    """

    # Configurations recorded before ``action`` existed (2026-12-05) used the rotation action.
    RECORDED_BEFORE: ClassVar[dict[str, str]] = {"action": "rotation"}

    action: str = "position"
    backbone: str = "densenet121"
    num_rotations: int = 16
    weights: str | None = None
    rotate: str = "input"
    depth_mean: float = 0.01
    depth_std: float = 0.03
    precision: str = "float32"

    def __post_init__(self) -> None:
        if self.backbone not in BACKBONES:
            raise ConfigError("network.backbone",
                              f"must be one of {BACKBONES}, got {self.backbone!r}")
        if self.num_rotations < 1:
            raise ConfigError("network.num_rotations", "must be >= 1")
        if self.action not in ACTIONS:
            raise ConfigError("network.action", f"must be one of {ACTIONS}, got {self.action!r}")
        allowed = ("input", "none") if self.action == "position" else ("input", "features")
        if self.rotate not in allowed:
            raise ConfigError("network.rotate", f"must be one of {allowed} with the "
                                                f"{self.action} action, got {self.rotate!r}")
        if self.precision not in PRECISIONS:
            raise ConfigError("network.precision",
                              f"must be one of {PRECISIONS}, got {self.precision!r}")
        check_positive(self, "depth_std", prefix="network.")

    @property
    def q_maps(self) -> int:
        """Q maps the network outputs per heightmap: 1 for the position action, R for the
        rotation action."""
        return 1 if self.action == "position" else self.num_rotations


@dataclass(frozen=True)
class AgentConfig:
    """DQN agent (paper eq. 4-11) for terminal one-step episodes: the target is y = R, so the
    paper's discount gamma and target network have no setting (:mod:`vgs.grasping.agent`).

    Attributes:
        learning_rate: SGD learning rate (paper: 1e-4).
        momentum: SGD momentum (paper: 0.9).
        weight_decay: L2 weight decay.
        epsilon_start: Initial exploration rate (paper: 0.5).
        epsilon_end: Final exploration rate (paper: 0.1).
        random_episodes: Grasps chosen at random before the greedy phase (paper: 1000).
        replay_capacity: Stored transitions.
        replay_batch: Extra prioritised replays per episode.
        delta_q_threshold: Convergence threshold on Delta Q = |y - Q_eva| (eq. 10; |R - Q_eva|
            in training): the largest in the window must be below it.
        delta_q_window: Episodes over which Delta Q must stay under the threshold.
    """

    learning_rate: float = 1e-4
    momentum: float = 0.9
    weight_decay: float = 2e-5
    epsilon_start: float = 0.5
    epsilon_end: float = 0.1
    random_episodes: int = 1000
    replay_capacity: int = 5000
    replay_batch: int = 1
    delta_q_threshold: float = 0.02
    delta_q_window: int = 100

    # Removed 2026-12-05 (issue 40): with terminal one-step episodes they changed no result.
    # Recorded configurations that still hold them read as without them.
    RETIRED: ClassVar[tuple[str, ...]] = ("gamma", "target_update_period")

    def __post_init__(self) -> None:
        check_positive(self, "learning_rate", "delta_q_threshold", prefix="agent.")
        check_fraction(self, "momentum", "epsilon_start", "epsilon_end", prefix="agent.")
        for name in ("random_episodes", "replay_batch"):
            if getattr(self, name) < 0:
                raise ConfigError(f"agent.{name}", "must be >= 0")
        for name in ("replay_capacity", "delta_q_window"):
            if getattr(self, name) < 1:
                raise ConfigError(f"agent.{name}", "must be >= 1")


@dataclass(frozen=True)
class RewardConfig:
    """Rewards (paper eq. 5).

    Attributes:
        grasp: r_G for a successful grasp.
        assembly: r_AM when the assembly is faster than the threshold (VGS mode only).
        threshold_s: Assembly-time threshold [s]; ``None`` derives it from the assembly times
            of the random-exploration phase.
        threshold_percentile: Percentile of the exploration-phase times used when
            ``threshold_s`` is ``None``.
    """

    grasp: float = 0.3
    assembly: float = 0.7
    threshold_s: float | None = None
    threshold_percentile: float = 50.0

    def __post_init__(self) -> None:
        check_non_negative(self, "grasp", "assembly", prefix="reward.")
        if self.threshold_s is not None and not self.threshold_s > 0:
            raise ConfigError("reward.threshold_s", "must be > 0 when given")
        if not 0.0 < self.threshold_percentile < 100.0:
            raise ConfigError("reward.threshold_percentile", "must lie in (0, 100)")


@dataclass(frozen=True)
class TrainConfig:
    """Training run.

    Attributes:
        episodes: Grasp-and-assemble episodes in all (paper: 5000).
        checkpoint_every: Episodes between checkpoints (a multiple of ``parallel_episodes``).
        device: ``cpu``, ``cuda`` or ``auto``.
        parallel_episodes: K; 1 (default, as in the paper) runs grasp, assembly and update one
            episode after the other. K > 1 chooses the grasps of K consecutive episodes with the
            same network, runs their physics in K worker processes and then updates in episode
            order: for machines with many cores, the network's information is up to K - 1
            episodes older when it decides.
        assemble_baseline: Run the assembly after the baseline's training grasps (default, as
            in the paper). Its reward is the grasp's alone, so ``False`` (``no_assembly``
            rows) gives the same rewards, the same updates and the same networks at about a
            seventh of the simulation (0.28 s against 2.04 s of CPU per episode,
            ``benchmarks/bench_eval.py``), without the baseline's assembly times in the
            training table.
        stop_at_threshold: Stop a VGS training assembly once it has taken longer than the
            frozen reward threshold (``cutoff:<phase>`` rows): slower than the threshold it
            earns no assembly reward however it ends, so rewards, updates and networks are the
            same as with the whole assembly, and the training table's assembly times are
            censored at the threshold. A derived threshold moves during the exploration
            phase, whose assemblies therefore run whole; a given ``reward.threshold_s`` stops
            them from the first episode.
    """

    episodes: int = 5000
    checkpoint_every: int = 50
    device: str = "auto"
    parallel_episodes: int = 1
    assemble_baseline: bool = True
    stop_at_threshold: bool = False

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise ConfigError("train.episodes", "must be >= 1")
        if self.checkpoint_every < 1:
            raise ConfigError("train.checkpoint_every", "must be >= 1")
        if self.device not in ("cpu", "cuda", "auto"):
            raise ConfigError("train.device", f"must be cpu, cuda or auto, got {self.device!r}")
        if self.parallel_episodes < 1:
            raise ConfigError("train.parallel_episodes", "must be >= 1")
        if self.checkpoint_every % self.parallel_episodes:
            raise ConfigError("train.checkpoint_every",
                              f"must be a multiple of train.parallel_episodes "
                              f"({self.parallel_episodes}), so that a resumed run starts a batch")
