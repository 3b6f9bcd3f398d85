"""Configuration of the admittance controller and the assembly strategy."""

from __future__ import annotations

from dataclasses import dataclass

from vgs.config.checks import _non_negative, _positive
from vgs.errors import ConfigError


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
        press_force: Downward force of the search's touch-downs, the alignment and the
            insertion [N]. Sized to the grasp: at the lowest rim point, about 10 mm beside the
            pads, 5 N loads them with 0.05 N m; on an edge with friction 0.4 at a lever up to
            89 mm, with 0.18 N m: both under the moment limit below.
        search_tilt_deg: Tilt of the peg during the spiral search [deg]; its lowest rim point
            drops into the hole first and produces two-point contact.
        spiral_pitch: Radial growth per turn of the Archimedes spiral of touch-downs [m].
        hop_step: Distance between two touch-downs along the spiral [m] (from the centre the
            second lies half a turn on). At 6 deg the rim point sinks ``drop_threshold`` only
            within a strip about 10 mm wide along the lean, from 6 mm short of the hole's axis
            to its far wall (137 mm^2, 18 % of the hole: ``benchmarks/touchdown_geometry.py``):
            6 mm apart, a spiral can step over it, and a new search turns its spiral.
        search_radius: Largest spiral radius [m]; the spiral starts again from its centre
            beyond it (the hole lies within its own radius of the nominal position).
        drop_threshold: Depth of a touch-down below the plane (TCP height; the plane's is the
            approach's plane contact, or the highest of the last five touch-downs where they
            landed higher) that declares two-point contact [m];
            touch-downs do not rub, so neighbouring heights on the plane differ by hundredths
            of a millimetre.
        slide_speed: Free sliding speed of the slide under its bias [m/s] (the lateral
            damping is the bias over this speed, at least the contact loop's 300 N s/m:
            2 N / 6.5 mm/s = 308 N s/m); a quarter of it counts as still.
        three_point_force: Lateral bias of the slide [N]; the TCP at rest (the measured lateral
            force then balances it) and fallen into the hole: three-point contact.
        slide_press_force: Downward force during the slide [N]: light, so that friction at
            the edge (0.4 x 2 N) leaves the bias free to slide the peg.
        search_stiffness: Lateral admittance stiffness of the guarded descent to plane
            contact [N/m] (the touch-downs of the search are force-controlled laterally).
        insert_stiffness: Lateral admittance stiffness during insertion [N/m].
        moment_limit_fraction: The controller keeps the measured moment about the pinch axis
            under this fraction of the grasp's capacity
            (:func:`vgs.sim.rg2.grasp_moment_capacity`): its rotational stiffness in contact
            is the limit over 2 deg, and wiggles and turns stop at the limit.
        wiggle_amplitude_deg: Amplitude of the wiggle rotation [deg].
        wiggle_period: Duration of one alignment adjustment [s]: half for the turn towards
            upright (up to 3 deg), half for the wiggle. Turned faster (1 s), the arm's tracking
            error in height reached 2.4 mm and lifted the peg out of the hole
            (docs/assembly.md).
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
    spiral_pitch: float = 0.006
    search_radius: float = 0.02
    drop_threshold: float = 0.0005
    slide_speed: float = 0.0065
    three_point_force: float = 2.0
    slide_press_force: float = 2.0
    search_stiffness: float = 2000.0
    insert_stiffness: float = 300.0
    moment_limit_fraction: float = 0.5
    wiggle_amplitude_deg: float = 1.0
    wiggle_period: float = 3.0
    insert_speed: float = 0.003
    hop_step: float = 0.006
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
            "spiral_pitch", "hop_step", "search_radius", "drop_threshold", "slide_speed",
            "three_point_force", "slide_press_force", "approach_speed", "search_stiffness",
            "insert_stiffness", "wiggle_period", "insert_speed", prefix="assembly.",
        )
        if not 0.0 < self.moment_limit_fraction <= 1.0:
            raise ConfigError("assembly.moment_limit_fraction",
                              f"must lie in (0, 1], got {self.moment_limit_fraction!r}")
        _non_negative(self, "search_tilt_deg", "wiggle_amplitude_deg",
                      prefix="assembly.")
        for name, value in self.timeouts:
            if value <= 0:
                raise ConfigError(f"assembly.timeouts.{name}", f"must be > 0, got {value}")

    def timeout(self, phase: str) -> float:
        return dict(self.timeouts)[phase]
