"""Typed, frozen configuration of every component, nested into one :class:`ExperimentConfig`.

Units are SI throughout (metres, kilograms, seconds, newtons, radians) unless a field name says
otherwise (``*_mm``, ``*_deg``). Every dataclass validates itself in ``__post_init__`` and raises
:class:`vgs.errors.ConfigError` naming the offending field, so bad input never reaches the physics.

Named profiles (:data:`PROFILES`): ``smoke`` (seconds, for tests), ``quick`` (minutes on a 2-core
CPU), ``medium`` (1.5-2 hours there) and ``paper`` (the paper's budget: 5000 training grasps,
1000 test assemblies).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any

from vgs.errors import ConfigError, VGSError


def _positive(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ConfigError(f"{prefix}{name}", f"must be a positive number, got {value!r}")


def _non_negative(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise ConfigError(f"{prefix}{name}", f"must be >= 0, got {value!r}")


def _fraction(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
            raise ConfigError(f"{prefix}{name}", f"must lie in [0, 1], got {value!r}")


# ----------------------------------------------------------------------------------------------
# Cell
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PegConfig:
    """The peg: a plain cylinder (paper 4.1: 100 mm long, 30 mm diameter, 0.55 kg, no chamfer).

    Attributes:
        diameter: Peg diameter [m].
        length: Peg length [m].
        mass: Peg mass [kg].
        friction: Sliding friction coefficient of the peg surface.
    """

    diameter: float = 0.030
    length: float = 0.100
    mass: float = 0.55
    friction: float = 0.4

    def __post_init__(self) -> None:
        _positive(self, "diameter", "length", "mass", "friction", prefix="peg.")
        if self.length < 2 * 0.025:
            raise ConfigError("peg.length", "must be at least 50 mm so the RG2 pads fit on it")

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter


@dataclass(frozen=True)
class HoleConfig:
    """The hole block (paper 4.1: 1 mm clearance, no chamfer).

    Attributes:
        clearance: Diametral clearance: hole diameter minus nominal peg diameter [m].
        depth: Depth of the hole [m]; must exceed the insertion depth K.
        outer_radius: Outer radius of the block [m].
        segments: Number of convex wedges that approximate the round hole. With the wedges' inner
            faces tangent to the hole circle, the inner surface lies between r and
            r / cos(pi / segments); 32 wedges keep it within 0.08 mm for r = 15.5 mm.
        nominal_xy: Nominal hole centre on the table, world frame [m].
        randomize: Displace the hole every episode uniformly inside a disk whose area equals the
            hole's area (paper 3.2), i.e. within the hole radius of ``nominal_xy``.
        friction: Sliding friction coefficient of the hole surfaces.
        peg_diameter: Diameter of the nominal peg the hole is made for [m]; the hole's diameter
            is this plus the clearance. The command line starts it at the nominal 30 mm, so
            ``--peg-diameter`` changes the peg and not the hole.
    """

    clearance: float = 0.001
    depth: float = 0.045
    outer_radius: float = 0.060
    segments: int = 32
    nominal_xy: tuple[float, float] = (0.42, 0.22)
    randomize: bool = True
    friction: float = 0.4
    peg_diameter: float = 0.030

    def __post_init__(self) -> None:
        if not (math.isfinite(self.clearance) and self.clearance > 0):
            raise ConfigError("hole.clearance", f"must be > 0, got {self.clearance!r}")
        _positive(self, "depth", "outer_radius", "friction", "peg_diameter", prefix="hole.")
        if self.segments < 8:
            raise ConfigError("hole.segments", f"must be >= 8, got {self.segments}")
        if self.outer_radius <= self.diameter / 2 + 0.005:
            raise ConfigError("hole.outer_radius", "must exceed the hole radius by at least 5 mm")

    @property
    def diameter(self) -> float:
        return self.peg_diameter + self.clearance

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def surface_tolerance(self) -> float:
        """Largest radial deviation of the polygonal inner surface from the true circle [m]."""
        return self.radius * (1.0 / math.cos(math.pi / self.segments) - 1.0)


@dataclass(frozen=True)
class GripperConfig:
    """OnRobot RG2 (datasheet: stroke 0-110 mm, gripping force 3-40 N, 0.65 kg).

    Attributes:
        force: Force-limited closing force per finger pair [N], 3-40 N on the RG2.
        stroke: Full opening [m].
        pad_friction: Sliding friction of the finger pads against the peg (rubber-faced pads
            on a machined metal peg: about 1).
        pad_torsional_friction: MuJoCo's torsional coefficient of the pad contacts [m] (the
            torque limit of one contact point is this times its normal force). Each pad's line
            contact is two point contacts placed so that their sliding friction resists the
            line's torsion, mu F L / 4 (:func:`vgs.sim.rg2.pad_contact_half_length`); the
            torsional term stands only for each point's own contact patch, about (2/3) mu a
            for a patch of radius a = 1.5 mm: 1 mm. It also lets MuJoCo's no-slip solver pin
            the contact: with ``condim=3`` pads one iteration leaves the peg creeping.
        pad_rolling_friction: Rolling friction of the pads [m] (0: none; > 0 gives the pads
            ``condim=6``).
        closing_speed: Finger closing speed [m/s] (RG2: about 0.11 m/s full stroke in 1 s).
    """

    force: float = 40.0
    stroke: float = 0.110
    pad_friction: float = 1.0
    pad_torsional_friction: float = 0.001
    pad_rolling_friction: float = 0.0
    closing_speed: float = 0.11

    def __post_init__(self) -> None:
        if not (3.0 <= self.force <= 40.0):
            raise ConfigError("gripper.force", f"the RG2 grips with 3-40 N, got {self.force!r}")
        _positive(self, "stroke", "pad_friction", "closing_speed", prefix="gripper.")
        _non_negative(self, "pad_torsional_friction", "pad_rolling_friction", prefix="gripper.")


@dataclass(frozen=True)
class FTSensorConfig:
    """Wrist force/torque sensor between flange and gripper.

    Attributes:
        force_noise: Standard deviation of white noise on each force axis [N].
        torque_noise: Standard deviation of white noise on each torque axis [N m].
        cutoff_hz: First-order low-pass filter cut-off [Hz]; 0 disables the filter.
    """

    force_noise: float = 0.05
    torque_noise: float = 0.002
    cutoff_hz: float = 30.0

    def __post_init__(self) -> None:
        _non_negative(self, "force_noise", "torque_noise", "cutoff_hz", prefix="ft.")


@dataclass(frozen=True)
class CameraConfig:
    """Overhead RGB-D camera reprojected to an orthographic heightmap.

    Attributes:
        size: Heightmap side [px].
        pixel_size: Metres per pixel.
        center_xy: Workspace centre in the world frame [m].
        height: Camera height above the table [m] (ray origins).
        depth_noise: Standard deviation of depth noise [m].
    """

    size: int = 224
    pixel_size: float = 0.002
    center_xy: tuple[float, float] = (0.42, -0.12)
    height: float = 0.8
    depth_noise: float = 0.0

    def __post_init__(self) -> None:
        if self.size < 16:
            raise ConfigError("camera.size", f"must be >= 16 px, got {self.size}")
        _positive(self, "pixel_size", "height", prefix="camera.")
        _non_negative(self, "depth_noise", prefix="camera.")

    @property
    def extent(self) -> float:
        """Side of the square workspace [m]."""
        return self.size * self.pixel_size


@dataclass(frozen=True)
class SimConfig:
    """Physics settings.

    Attributes:
        timestep: MuJoCo time step [s].
        control_decimation: Physics steps per controller update (controller rate =
            1 / (timestep * control_decimation)).
        contact_timeconst: Time constant of the peg/hole/pad contacts [s] (solref); must be at
            least twice the time step.
        impratio: Ratio of frictional to normal constraint impedance (MuJoCo ``impratio``);
            values > 1 make static friction stiffer, which a friction grasp needs.
        noslip_iterations: Iterations of MuJoCo's no-slip post-solver (0 = off). MuJoCo's
            friction is soft: without it a peg held 35 mm from its centre of mass (0.19 N m,
            under half the grasp's capacity) creeps round in the pads at about 3 deg/s; one
            iteration pins every sticking contact, so the grasp holds below its capacity and
            slips above it (tests/test_grasp_hold.py, docs/cell.md "The grasp").
    """

    timestep: float = 0.002
    control_decimation: int = 5
    contact_timeconst: float = 0.004
    impratio: float = 10.0
    noslip_iterations: int = 1

    def __post_init__(self) -> None:
        _positive(self, "timestep", "contact_timeconst", "impratio", prefix="sim.")
        if self.control_decimation < 1:
            raise ConfigError("sim.control_decimation", "must be >= 1")
        if self.contact_timeconst < 2 * self.timestep:
            raise ConfigError("sim.contact_timeconst", "must be at least twice sim.timestep")

    @property
    def control_dt(self) -> float:
        return self.timestep * self.control_decimation


@dataclass(frozen=True)
class CellConfig:
    """The whole assembly cell.

    A peg wider than the hole is a valid cell (the clearance tests build one to show that it does
    not go in); the command line refuses it (:func:`vgs.cli.check_hole_fits`).
    """

    peg: PegConfig = field(default_factory=PegConfig)
    hole: HoleConfig = field(default_factory=HoleConfig)
    gripper: GripperConfig = field(default_factory=GripperConfig)
    ft: FTSensorConfig = field(default_factory=FTSensorConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    sim: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        if self.hole.depth > self.peg.length:
            raise ConfigError("hole.depth", "must not exceed the peg length")


# ----------------------------------------------------------------------------------------------
# Control and assembly
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ControllerConfig:
    """Cartesian admittance controller on top of stiff joint servos.

    The commanded TCP pose x_c follows the virtual dynamics
    ``M_a * xdd_c + D_a * xd_c + K_a * (x_c - x_ref) = f_ext`` (per axis, translation and
    rotation separately), where f_ext is the tared F/T wrench. ``D_a`` is chosen for critical
    damping: ``D_a = 2 * zeta * sqrt(K_a * M_a)``.

    Attributes:
        trans_stiffness: K_a, translation [N/m].
        rot_stiffness: K_a, rotation [N m/rad].
        trans_mass: M_a, translation [kg].
        rot_inertia: M_a, rotation [kg m^2].
        damping_ratio: zeta of the virtual dynamics.
        joint_kp: Joint servo stiffness [N m/rad] of the UR5 position loop (MuJoCo position
            actuators; implicit damping keeps them stable at the physics time step).
        joint_kv: Joint servo damping [N m s/rad].
        force_damping: Damping D of force-controlled axes (K = 0) [N s/m]: a force error of
            10 N moves the TCP at 10 / D m/s.
        max_speed: Largest commanded TCP speed [m/s].
        max_angular_speed: Largest commanded TCP angular speed [rad/s].
    """

    trans_stiffness: float = 2000.0
    rot_stiffness: float = 40.0
    trans_mass: float = 4.0
    rot_inertia: float = 0.02
    damping_ratio: float = 1.0
    joint_kp: tuple[float, ...] = (6000.0, 6000.0, 4000.0, 1500.0, 1500.0, 1500.0)
    joint_kv: tuple[float, ...] = (300.0, 300.0, 200.0, 40.0, 40.0, 40.0)
    force_damping: float = 1500.0
    max_speed: float = 0.25
    max_angular_speed: float = 1.5

    def __post_init__(self) -> None:
        _positive(
            self, "trans_stiffness", "rot_stiffness", "trans_mass", "rot_inertia",
            "damping_ratio", "force_damping", "max_speed", "max_angular_speed",
            prefix="controller.",
        )
        if len(self.joint_kp) != 6 or len(self.joint_kv) != 6:
            raise ConfigError("controller.joint_kp", "needs six values, one per UR5 joint")


@dataclass(frozen=True)
class AssemblyConfig:
    """The compliance-based assembly module (paper 3.2, Figure 5).

    Attributes:
        insertion_depth: K in delta = arctan(clearance / K) [m] (paper eq. 1).
        approach_height: Height of the peg tip above the hole surface before contact [m].
        approach_speed: Speed of the guarded descent to plane contact [m/s]; the descent
            starts where the longest peg the product data allows would clear the surface.
        contact_force: Force threshold that declares plane contact [N].
        press_force: Constant downward force during search, slide, alignment and insertion
            [N]. Sized to the grasp: pressed at the rim (15 mm off the axis) and dragged with
            friction 0.4 at a lever up to 89 mm, 5 N loads the pads with about 0.25 N m, under
            the moment limit below.
        search_tilt_deg: Tilt of the peg during the spiral search [deg]; the leading rim point
            drops into the hole first and produces two-point contact.
        spiral_pitch: Radial growth of the Archimedes spiral per turn [m]; by default the
            hole's clearance plus the peg radius times the search tilt's sine is not needed: a
            pitch of a few millimetres makes the leading rim point sweep every point.
        spiral_speed: Tangential speed of the spiral [m/s].
        search_radius: Largest spiral radius [m]; the spiral starts again from its centre
            beyond it (the hole lies within its own radius of the nominal position).
        drop_threshold: Drop of the TCP below the plane-contact height that declares two-point
            contact [m].
        slide_speed: Free sliding speed of the slide under its bias [m/s] (the lateral
            damping is the bias over this speed); a quarter of it counts as still.
        three_point_force: Lateral bias of the slide along the measured reaction [N]; when the
            measured lateral force balances it and the TCP stands still: three-point contact.
        slide_press_force: Downward force during the slide [N]: light, so that friction at
            the edge (0.4 x 2 N) leaves the bias free to slide the peg.
        search_stiffness: Lateral admittance stiffness during the spiral search [N/m].
        insert_stiffness: Lateral admittance stiffness during insertion [N/m].
        moment_limit_fraction: The controller keeps the measured moment about the pinch axis
            under this fraction of the grasp's capacity
            (:func:`vgs.sim.rg2.grasp_moment_capacity`): its rotational stiffness in contact
            is the limit over 2 deg, and wiggles and turns stop at the limit.
        wiggle_amplitude_deg: Amplitude of the wiggle rotation [deg].
        wiggle_period: Period of one wiggle [s].
        align_gain: Rotation per measured contact moment [rad / (N m)] in the alignment phase.
        insert_speed: Reference speed of the insertion [m/s]: a descent slower than a quarter
            of it over 0.25 s counts as a stall (the push itself is force-controlled: 5 N at
            1500 N s/m moves the peg at about 3.3 mm/s when nothing resists).
        timeouts: Per-phase timeouts in simulated seconds.
    """

    insertion_depth: float = 0.030
    approach_height: float = 0.010
    approach_speed: float = 0.01
    contact_force: float = 2.0
    press_force: float = 5.0
    search_tilt_deg: float = 6.0
    spiral_pitch: float = 0.004
    spiral_speed: float = 0.01
    search_radius: float = 0.02
    drop_threshold: float = 0.001
    slide_speed: float = 0.01
    three_point_force: float = 2.0
    slide_press_force: float = 2.0
    search_stiffness: float = 2000.0
    insert_stiffness: float = 300.0
    moment_limit_fraction: float = 0.5
    wiggle_amplitude_deg: float = 1.0
    wiggle_period: float = 1.0
    align_gain: float = 0.5
    insert_speed: float = 0.003
    timeouts: tuple[tuple[str, float], ...] = (
        ("transport", 20.0),
        ("approach", 20.0),
        ("search", 120.0),
        ("slide", 30.0),
        ("align", 60.0),
        ("insert", 30.0),
    )

    def __post_init__(self) -> None:
        _positive(
            self, "insertion_depth", "approach_height", "contact_force", "press_force",
            "spiral_pitch", "spiral_speed", "search_radius", "drop_threshold", "slide_speed",
            "three_point_force", "slide_press_force", "approach_speed", "search_stiffness",
            "insert_stiffness", "wiggle_period", "insert_speed", prefix="assembly.",
        )
        if not 0.0 < self.moment_limit_fraction <= 1.0:
            raise ConfigError("assembly.moment_limit_fraction",
                              f"must lie in (0, 1], got {self.moment_limit_fraction!r}")
        _non_negative(self, "search_tilt_deg", "wiggle_amplitude_deg", "align_gain",
                      prefix="assembly.")
        for name, value in self.timeouts:
            if value <= 0:
                raise ConfigError(f"assembly.timeouts.{name}", f"must be > 0, got {value}")

    def timeout(self, phase: str) -> float:
        return dict(self.timeouts)[phase]


# ----------------------------------------------------------------------------------------------
# Grasp learning
# ----------------------------------------------------------------------------------------------

BACKBONES = ("densenet121", "light")
ROTATE_MODES = ("input", "features")
PRECISIONS = ("float32", "bfloat16")


@dataclass(frozen=True)
class NetworkConfig:
    """Fully convolutional grasp Q network (paper 3.1).

    Attributes:
        backbone: ``densenet121`` (paper) or ``light`` (fast CPU runs).
        num_rotations: Number of grasp orientations R over 360 degrees, theta_k = 2 pi k / R
            (k and k + R/2 are the same two-finger grasp).
        weights: Optional path of a local weights file for the trunks.
        rotate: ``input`` (rotate the heightmap R times before the trunks, as VPG and the paper
            do) or ``features`` (trunks run once, orientation handled after them; about 14x
            faster decisions with DenseNet-121 on a CPU, see docs/grasping.md; not in the paper).
        depth_mean: Mean subtracted from the depth heightmap [m].
        depth_std: Scale dividing the depth heightmap [m].
        precision: ``float32`` (default) or ``bfloat16``: the forward passes (decisions, TD
            targets, updates) under ``torch.autocast`` in bfloat16, weights, optimiser and loss
            in float32. About 3x faster DenseNet-121 decisions on a CPU with AMX or
            AVX512-BF16 (docs/grasping.md); Q values agree with float32 within bfloat16
            rounding. A compute setting, not part of the architecture: a checkpoint loads
            under either.
    """

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
        if self.rotate not in ROTATE_MODES:
            raise ConfigError("network.rotate",
                              f"must be one of {ROTATE_MODES}, got {self.rotate!r}")
        if self.precision not in PRECISIONS:
            raise ConfigError("network.precision",
                              f"must be one of {PRECISIONS}, got {self.precision!r}")
        _positive(self, "depth_std", prefix="network.")


@dataclass(frozen=True)
class AgentConfig:
    """DQN agent (paper eq. 4-11).

    Attributes:
        learning_rate: SGD learning rate (paper: 1e-4).
        momentum: SGD momentum (paper: 0.9).
        weight_decay: L2 weight decay.
        gamma: Future discount (paper: 0.5); unused by vgs train, whose grasps are terminal
            one-step episodes (target y = R).
        epsilon_start: Initial exploration rate (paper: 0.5).
        epsilon_end: Final exploration rate (paper: 0.1).
        random_episodes: Grasps chosen at random before the greedy phase (paper: 1000).
        target_update_period: Updates between copies of the evaluation into the target network
            (which vgs train never reads: its target is y = R).
        replay_capacity: Stored transitions.
        replay_batch: Extra prioritised replays per episode.
        delta_q_threshold: Convergence threshold on Delta Q = |y - Q_eva| (eq. 10; |R - Q_eva|
            in training): the largest in the window must be below it.
        delta_q_window: Episodes over which Delta Q must stay under the threshold.
    """

    learning_rate: float = 1e-4
    momentum: float = 0.9
    weight_decay: float = 2e-5
    gamma: float = 0.5
    epsilon_start: float = 0.5
    epsilon_end: float = 0.1
    random_episodes: int = 1000
    target_update_period: int = 50
    replay_capacity: int = 5000
    replay_batch: int = 1
    delta_q_threshold: float = 0.02
    delta_q_window: int = 100

    def __post_init__(self) -> None:
        _positive(self, "learning_rate", "delta_q_threshold", prefix="agent.")
        _fraction(self, "momentum", "gamma", "epsilon_start", "epsilon_end", prefix="agent.")
        for name in ("random_episodes", "replay_batch"):
            if getattr(self, name) < 0:
                raise ConfigError(f"agent.{name}", "must be >= 0")
        for name in ("target_update_period", "replay_capacity", "delta_q_window"):
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
        _non_negative(self, "grasp", "assembly", prefix="reward.")
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
    """

    episodes: int = 5000
    checkpoint_every: int = 50
    device: str = "auto"
    parallel_episodes: int = 1

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


@dataclass(frozen=True)
class EvalConfig:
    """Evaluation: the test episodes of one policy on one condition (paper 4.2).

    Attributes:
        episodes: Test episodes per policy and condition (paper: 1000).
        mass_range: The ``mass`` condition's peg mass factor is uniform in 1 +- this.
        length_range: The ``length`` condition's peg length factor is uniform in 1 +- this; the
            mass follows the length.
    """

    episodes: int = 1000
    mass_range: float = 0.15
    length_range: float = 0.15

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise ConfigError("eval.episodes", "must be >= 1")
        _fraction(self, "mass_range", "length_range", prefix="eval.")


@dataclass(frozen=True)
class ReproduceConfig:
    """What ``vgs reproduce`` runs besides one training per mode and the evaluations.

    Attributes:
        train_seeds: Root seeds of the training runs; each seed trains the baseline and VGS
            (the paper reports one run per method).
        conditions: Test conditions (``nominal``, ``mass``, ``length``; paper 4.2).
        reference_policies: Extra heuristic policies evaluated beside the learned ones
            (``center``, ``random``).
        sweep_offsets: Grasp offsets of the grasp-position sweep (0: no sweep).
        sweep_trials: Trials per offset of the sweep.
        eval_seed: Root seed of the test episodes (the same scenes for every policy).
    """

    train_seeds: tuple[int, ...] = (0,)
    conditions: tuple[str, ...] = ("nominal", "mass", "length")
    reference_policies: tuple[str, ...] = ("center",)
    sweep_offsets: int = 9
    sweep_trials: int = 20
    eval_seed: int = 2023

    def __post_init__(self) -> None:
        if not self.train_seeds:
            raise ConfigError("reproduce.train_seeds", "need at least one seed")
        bad = [c for c in self.conditions if c not in ("nominal", "mass", "length")]
        if bad or not self.conditions:
            raise ConfigError("reproduce.conditions",
                              f"must be a non-empty subset of nominal, mass, length; got {bad}")
        bad = [p for p in self.reference_policies if p not in ("center", "random")]
        if bad:
            raise ConfigError("reproduce.reference_policies",
                              f"must be center and/or random, got {bad}")
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
        agent=AgentConfig(random_episodes=30, target_update_period=10, delta_q_window=20),
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
        agent=AgentConfig(random_episodes=240, target_update_period=25, delta_q_window=50),
        train=TrainConfig(episodes=1200, checkpoint_every=25),
        eval=EvalConfig(episodes=250),
        reproduce=ReproduceConfig(sweep_offsets=0),
    )


def _smoke() -> ExperimentConfig:
    return ExperimentConfig(
        name="smoke",
        network=NetworkConfig(backbone="light", num_rotations=4),
        agent=AgentConfig(random_episodes=2, target_update_period=2, delta_q_window=2,
                          replay_capacity=64),
        train=TrainConfig(episodes=4, checkpoint_every=2),
        eval=EvalConfig(episodes=4),
        reproduce=ReproduceConfig(sweep_offsets=3, sweep_trials=1),
    )


PROFILES = {"smoke": _smoke, "quick": _quick, "medium": _medium, "paper": _paper}


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


NO_SUCH_FIELD = "no such configuration field"


def override(cfg: Any, path: str, value: Any) -> Any:
    """Return a copy of a nested frozen dataclass with the dotted field ``path`` set to ``value``.

    Example: ``override(cfg, "cell.peg.mass", 0.6)``. Validation runs again on every level.

    Raises:
        ConfigError: If the path names no field (the error names the whole path) or the value is
            invalid (the error names the field as its validator does, e.g. ``hole.clearance``).
    """
    head, _, rest = path.partition(".")
    if not is_dataclass(cfg) or head not in {f.name for f in fields(cfg)}:
        raise ConfigError(path, NO_SUCH_FIELD)
    if rest:
        try:
            inner = override(getattr(cfg, head), rest, value)
        except ConfigError as exc:
            if exc.field == rest and exc.message == NO_SUCH_FIELD:  # name it from the top
                raise ConfigError(path, exc.message) from None
            raise
        return replace(cfg, **{head: inner})
    return replace(cfg, **{head: value})


def to_dict(cfg: Any) -> dict[str, Any]:
    """Plain-dict view (for JSON) of a configuration."""
    return dataclasses.asdict(cfg)


def from_dict(cls: type, data: dict[str, Any]) -> Any:
    """Rebuild a nested frozen dataclass from :func:`to_dict` output."""
    kwargs = {}
    for f in fields(cls):
        if f.name not in data:
            continue
        value = data[f.name]
        ftype = f.type if isinstance(f.type, type) else globals().get(str(f.type), None)
        if isinstance(ftype, type) and is_dataclass(ftype) and isinstance(value, dict):
            value = from_dict(ftype, value)
        elif isinstance(value, list):
            value = tuple(tuple(v) if isinstance(v, list) else v for v in value)
        kwargs[f.name] = value
    return cls(**kwargs)


def same_config(saved: Any, cfg: Any) -> bool:
    """Whether ``saved`` (:func:`to_dict` output, e.g. read from a run's JSON) describes ``cfg``.

    Fields added to vgs since ``saved`` was written take their defaults, so folders made by an
    earlier version stay resumable as long as nothing they recorded differs. Unknown fields or
    values the dataclasses reject make it a different configuration.
    """
    if not isinstance(saved, dict):
        return False
    try:
        saved_cfg = from_dict(type(cfg), saved)
    except (TypeError, ValueError, VGSError):
        return False
    return json.dumps(to_dict(saved_cfg)) == json.dumps(to_dict(cfg))

