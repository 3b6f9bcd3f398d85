"""Configuration of the cell: peg, hole, gripper, force-torque sensor, camera, simulation."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from vgs.config.checks import check_non_negative, check_positive, is_finite, shown
from vgs.errors import ConfigError

COM_MARKINGS = ("visible", "hidden")


@dataclass(frozen=True)
class PegConfig:
    """The peg: a plain cylinder (paper 4.1: 100 mm long, 30 mm diameter, 0.55 kg, no chamfer).

    Attributes:
        diameter: Peg diameter [m].
        length: Peg length [m].
        mass: Peg mass [kg].
        friction: Sliding friction coefficient of the peg surface.
        com_shift_mm: Distance of the centre of mass from the middle along the axis, towards
            the heavy end [mm] (0: a uniform peg). A denser insert fills the last quarter of
            the length at that end (the outer shape is unchanged), so the shift can reach
            3/8 of the length less 1 mm (the insert's centre). Ground truth: the controller
            knows the nominal peg only.
        com_marking: ``visible``: the heavy end's last 10 mm painted blue (a coat 0.3 mm thick
            the camera sees); ``hidden``: no mark. Only with a shift.
    """

    diameter: float = 0.030
    length: float = 0.100
    mass: float = 0.55
    friction: float = 0.4
    com_shift_mm: float = 0.0
    com_marking: str = "visible"

    def __post_init__(self) -> None:
        check_positive(self, "diameter", "length", "mass", "friction", prefix="peg.")
        if self.length < 2 * 0.025:
            raise ConfigError("peg.length", "must be at least 50 mm so the RG2 pads fit on it")
        shift = self.com_shift_mm
        limit = 375.0 * self.length - 1.0  # 3/8 of the length [mm], less 1 mm
        if isinstance(shift, bool) or not isinstance(shift, (int, float)) \
                or not math.isfinite(shift) or not 0.0 <= shift <= limit:
            raise ConfigError("peg.com_shift_mm", f"must lie in [0, {limit:g}] mm (3/8 of the "
                                                  f"length less 1 mm), got {shift!r}")
        if self.com_marking not in COM_MARKINGS:
            raise ConfigError("peg.com_marking", f"must be one of {', '.join(COM_MARKINGS)}, "
                                                 f"got {self.com_marking!r}")

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
        if not (is_finite(self.clearance) and self.clearance > 0):
            raise ConfigError("hole.clearance", f"must be > 0, got {shown(self.clearance)}")
        check_positive(self, "depth", "outer_radius", "friction", "peg_diameter", prefix="hole.")
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
        stiction: Give the pads a stick state (:mod:`vgs.sim.stiction`): the grasp holds
            without creeping until its load reaches the pads' friction limit. False leaves
            MuJoCo's velocity-regularised friction alone (the cell before 2026-12-02).
    """

    force: float = 40.0
    stroke: float = 0.110
    pad_friction: float = 1.0
    pad_torsional_friction: float = 0.001
    pad_rolling_friction: float = 0.0
    closing_speed: float = 0.11
    stiction: bool = True

    def __post_init__(self) -> None:
        if not (3.0 <= self.force <= 40.0):
            raise ConfigError("gripper.force", f"the RG2 grips with 3-40 N, got {self.force!r}")
        check_positive(self, "stroke", "pad_friction", "closing_speed", prefix="gripper.")
        check_non_negative(self, "pad_torsional_friction", "pad_rolling_friction",
                           prefix="gripper.")


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
        check_non_negative(self, "force_noise", "torque_noise", "cutoff_hz", prefix="ft.")


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
        check_positive(self, "pixel_size", "height", prefix="camera.")
        check_non_negative(self, "depth_noise", prefix="camera.")

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
        check_positive(self, "timestep", "contact_timeconst", "impratio", prefix="sim.")
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
