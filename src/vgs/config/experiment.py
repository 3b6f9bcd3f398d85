"""Configuration of an experiment: evaluation, reproduction, the whole tree, the profiles."""

from __future__ import annotations

from dataclasses import dataclass, field

from vgs.config.cell import CellConfig
from vgs.config.conditions import CONDITIONS, PAPER_CONDITIONS, EvalConfig
from vgs.config.control import AssemblyConfig, ControllerConfig
from vgs.config.learning import AgentConfig, NetworkConfig, RewardConfig, TrainConfig
from vgs.errors import ConfigError

# The reference policies of vgs evaluate (vgs.rollout.policies builds them): the centre
# heuristic, a random peg pixel, and the centre-of-mass oracle (ground truth, analysis only).
REFERENCE_POLICIES = ("center", "random", "com-oracle")


@dataclass(frozen=True)
class ReproduceConfig:
    """What ``vgs reproduce`` runs besides one training per mode and the evaluations.

    Attributes:
        train_seeds: Root seeds of the training runs; each seed trains the baseline and VGS
            (the paper reports one run per method).
        conditions: Test conditions (the paper's ``nominal``, ``mass``, ``length``, 4.2;
            ``com``, ``com-hidden``, ``com-spread``: :mod:`vgs.config.conditions`).
        reference_policies: Extra reference policies evaluated beside the learned ones
            (:data:`REFERENCE_POLICIES`: ``center``, ``random``, ``com-oracle``).
        sweep_offsets: Grasp offsets of the grasp-position sweep (0: no sweep).
        sweep_trials: Trials per offset of the sweep.
        eval_seed: Root seed of the test episodes (the same scenes for every policy).
    """

    train_seeds: tuple[int, ...] = (0,)
    conditions: tuple[str, ...] = PAPER_CONDITIONS
    reference_policies: tuple[str, ...] = ("center",)
    sweep_offsets: int = 9
    sweep_trials: int = 20
    eval_seed: int = 2023

    def __post_init__(self) -> None:
        if not self.train_seeds:
            raise ConfigError("reproduce.train_seeds", "need at least one seed")
        bad = [c for c in self.conditions if c not in CONDITIONS]
        if bad or not self.conditions:
            raise ConfigError("reproduce.conditions",
                              f"must be a non-empty subset of {', '.join(CONDITIONS)}; got {bad}")
        bad = [p for p in self.reference_policies if p not in REFERENCE_POLICIES]
        if bad:
            raise ConfigError("reproduce.reference_policies",
                              f"must be a subset of {', '.join(REFERENCE_POLICIES)}, got {bad}")
        if self.sweep_offsets < 0 or self.sweep_trials < 1:
            raise ConfigError("reproduce.sweep_offsets", "offsets >= 0 and trials >= 1")


@dataclass(frozen=True)
class ExperimentConfig:
    """Everything one experiment needs.

    Attributes:
        name: Profile name, recorded in ``reproduce.json`` and a sweep's ``summary.json`` and
            shown in a reproduction report's title.
        seed: Root seed of a training run (network initialisation, exploration, episode scenes)
            and the default seed of ``vgs demo`` and ``vgs sweep``; ``vgs reproduce`` trains
            with each of ``reproduce.train_seeds`` instead.
    """

    name: str = "paper"
    seed: int = 0
    cell: CellConfig = field(default_factory=CellConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    assembly: AssemblyConfig = field(default_factory=AssemblyConfig)
    network: NetworkConfig = field(default_factory=NetworkConfig)
    agent: AgentConfig = field(default_factory=AgentConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    train: TrainConfig = field(default_factory=TrainConfig)
    eval: EvalConfig = field(default_factory=EvalConfig)
    reproduce: ReproduceConfig = field(default_factory=ReproduceConfig)


def _paper() -> ExperimentConfig:
    return ExperimentConfig(name="paper")


def _quick() -> ExperimentConfig:
    # Sized to finish `vgs reproduce --profile quick` within 15 minutes on a 2-core CPU:
    # 2 x 80 training episodes side by side, 3 policies x 3 conditions x 12 test episodes, a
    # 5 x 3 sweep. Far too small to learn the grasp position; it shows the whole pipeline.
    return ExperimentConfig(
        name="quick",
        network=NetworkConfig(backbone="light", num_rotations=8),
        agent=AgentConfig(random_episodes=30, delta_q_window=20),
        train=TrainConfig(episodes=80, checkpoint_every=10),
        eval=EvalConfig(episodes=12),
        reproduce=ReproduceConfig(sweep_offsets=5, sweep_trials=3),
    )


def _medium() -> ExperimentConfig:
    # Sized to fit `vgs reproduce --profile medium` into one working session (1.5-2 h) on a
    # 2-core CPU, 15x the quick profile's training and 20x its tests: 2 x 1200 training episodes
    # side by side (the first 240 random: the paper's 20 %), 3 policies x 3 conditions x 250
    # test episodes, no sweep (the sweep has its own command). The light backbone at the quick
    # profile's R = 8 keeps the network's share of the time small; the simulation is the rest.
    return ExperimentConfig(
        name="medium",
        network=NetworkConfig(backbone="light", num_rotations=8),
        agent=AgentConfig(random_episodes=240, delta_q_window=50),
        train=TrainConfig(episodes=1200, checkpoint_every=25),
        eval=EvalConfig(episodes=250),
        reproduce=ReproduceConfig(sweep_offsets=0),
    )


def _paper_light() -> ExperimentConfig:
    # The paper's protocol (5000 grasps per policy, the first 1000 random, 1000 tests per policy
    # and condition) sized for a 2-core CPU: the paper's position action (the network picks a
    # pixel; the jaws close across the perceived peg axis, the heightmap turned once into the
    # jaws' frame), the light backbone, the baseline's training grasps without the assembly
    # its reward does not use, VGS's training assemblies stopped at the frozen reward
    # threshold (the same rewards either way), two parallel training episodes per run, the
    # network's forward passes in bfloat16 (2.1x faster on a CPU with bfloat16 units;
    # docs/training.md), and the reference policy and the sweep left to their own commands
    # (`vgs evaluate --policy center`, `vgs sweep`). `--set network.action=rotation` runs the
    # rotation action space of visual-pushing-grasping (R = 16) instead.
    return ExperimentConfig(
        name="paper-light",
        network=NetworkConfig(backbone="light", num_rotations=16, precision="bfloat16"),
        train=TrainConfig(parallel_episodes=2, assemble_baseline=False,
                          stop_at_threshold=True),
        reproduce=ReproduceConfig(reference_policies=(), sweep_offsets=0),
    )


def _smoke() -> ExperimentConfig:
    return ExperimentConfig(
        name="smoke",
        network=NetworkConfig(backbone="light", num_rotations=4),
        agent=AgentConfig(random_episodes=2, delta_q_window=2, replay_capacity=64),
        train=TrainConfig(episodes=4, checkpoint_every=2),
        eval=EvalConfig(episodes=4),
        reproduce=ReproduceConfig(sweep_offsets=3, sweep_trials=1),
    )


PROFILES = {"smoke": _smoke, "quick": _quick, "medium": _medium, "paper": _paper,
            "paper-light": _paper_light}


def profile(name: str) -> ExperimentConfig:
    """Return the named profile.

    Raises:
        ConfigError: If the profile is unknown.
    """
    try:
        return PROFILES[name]()
    except KeyError:
        raise ConfigError(
            "profile", f"unknown profile {name!r}; choose from {sorted(PROFILES)}"
        ) from None
