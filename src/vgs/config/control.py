"""Configuration of the admittance controller and the assembly strategy."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vgs.config.checks import check_fraction, check_non_negative, check_positive
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
        check_positive(
            self, "trans_stiffness", "rot_stiffness", "trans_mass", "rot_inertia",
            "damping_ratio", "force_damping", "max_speed", "max_angular_speed",
            prefix="controller.",
        )
        if len(self.joint_kp) != 6 or len(self.joint_kv) != 6:
            raise ConfigError("controller.joint_kp", "needs six values, one per UR5 joint")


# The assembly's phases and their default time-outs [simulated s]; every phase needs one.
_DEFAULT_TIMEOUTS: tuple[tuple[str, float], ...] = (
    ("transport", 20.0), ("approach", 20.0), ("search", 120.0), ("slide", 30.0),
    ("align", 60.0), ("insert", 30.0),
)
MAX_PHASE_TIMEOUT_S = 3600.0


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
            to its far wall (137 mm^2, 18 % of the hole; docs/assembly.md):
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
        rot_contact_damping: Least rotational admittance damping in contact [N m s/rad]. The
            lower end in contact is a lateral spring k_c at the lever h below the pads, a
            rotational stiffness k_c h^2 about them (about 250 N m/rad for MuJoCo's 4 ms
            contacts on a 0.55 kg peg at h = 85 mm); the discrete admittance loop at the
            control period dt stays stable for D > k_c h^2 dt (:mod:`vgs.control.admittance`).
        contact_damping: Least lateral admittance damping in contact [N s/m]: 3x the
            servo-loop minimum D > k_c dt of a contact spring k_c on the peg.
        entry_depth: Descent of the TCP below the three-point height that means the peg has
            entered the hole, one condition of the alignment's end [m].
        settle_time: Still time before each tare and after the transport's and the approach's
            moves [s].
        length_tolerance: The product data's length tolerance, a fraction of the nominal
            length: the transport and the approach clear the longest peg it allows.
        longer_end_margin: The transport hangs the peg's longer end down, the end away from
            the chosen grasp point along the peg the camera perceived, when the grasp lies
            more than this from the perceived middle [m]; within it the two ends are equally
            long to the perception's precision (two pixels of the 2 mm heightmap) and the F/T
            moment of the horizontal peg picks the side of its centre of mass.
        lost_width_fraction: The grasp watch: a finger width below this fraction of the peg's
            nominal diameter means the peg is lost.
        retry_lift: Lift of the TCP, above the first plane contact at least, before a new
            search [m].
        rot_compliance_angle_deg: Reference lead [deg] that loads the grasp to its moment
            limit: the rotational stiffness in contact is the limit over this angle (kept in
            degrees like the other angles; the controller converts it with ``math.radians``).
        slide_settle_time: Light press on the rim before the slide's bias [s].
        three_point_fraction: Fraction of ``D sin(tilt)`` (3.1 mm for the nominal 30 mm peg at
            6 deg) that the TCP at rest must lie below the plane contact for three-point
            contact: the tilted face inside the hole, its lowest rim point at the far wall,
            rests ``D sin(tilt)`` low; a face across the rim 3 mm beside the hole's axis 1.3
            mm, a face over the hole 2.2-2.7 mm.
        climb_travel: Lateral travel from the slide's deepest point, while rising, that means
            the peg climbs the far edge [m].
        still_time: Window of the slide's rest test [s]: moved less than a quarter of
            ``slide_speed`` over it, the TCP is still.
        max_retries: New searches after a wrong contact-state decision before the assembly
            gives up (a time-out of the phase that found it).
        align_step_deg: Largest turn towards upright of one alignment adjustment [deg]
            (converted with ``math.radians``).
        max_align_adjustments: Adjustments in one alignment before it is judged lost (a new
            search).
        max_insert_stalls: Consecutive stalled wiggles before the insertion is judged lost (a
            new search).
        plane_contact_margin: The approach's plane contact lies this far beyond the hole's
            reach (twice its radius from the nominal centre) [m].
        plane_window: Touch-downs whose highest (with the approach's plane contact) is the
            plane's height: at long levers the pads give a little and the peg turns further
            into its tilt over a search (0.8 deg, touch-downs 0.3 mm high at -26.25 mm); a
            touch-down more than half ``drop_threshold`` above the plane is not taken for it.
        hop_height: Lift of the lowest rim point above the plane between two touch-downs [m].
        hop_press_time: Press at each touch-down before the height is read [s].
        hop_lift_speed: Speed of the lift before each free-air move of the search [m/s].
        hop_speed: Free-air speed between touch-downs [m/s].
        hop_settle_time: Still time before each touch-down [s].
        hop_descent_speed: Speed of each touch-down's force-controlled descent [m/s].
        hop_rot_stiffness: Rotational admittance stiffness of a touch-down [N m/rad]: the 5 N
            press at the lowest rim point, about 10 mm beside the pads, turns the tool by 0.03
            deg; with the contact phases' compliance (6.4 N m/rad) each touch-down on an edge
            rocked the peg by tenths of a degree.
    """

    # A configuration recorded before longer_end_margin existed was run by a controller whose
    # F/T moment always picked the longer end: a margin of 1 m (every grasp lies within it).
    RECORDED_BEFORE: ClassVar[dict[str, float]] = {"longer_end_margin": 1.0}

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
    rot_contact_damping: float = 2.5
    contact_damping: float = 300.0
    entry_depth: float = 0.004
    settle_time: float = 0.3
    length_tolerance: float = 0.15
    longer_end_margin: float = 0.004
    lost_width_fraction: float = 0.8
    retry_lift: float = 0.012
    rot_compliance_angle_deg: float = 2.0
    slide_settle_time: float = 0.3
    three_point_fraction: float = 0.5
    climb_travel: float = 0.003
    still_time: float = 0.3
    max_retries: int = 3
    align_step_deg: float = 3.0
    max_align_adjustments: int = 15
    max_insert_stalls: int = 4
    plane_contact_margin: float = 0.004
    plane_window: int = 5
    hop_height: float = 0.001
    hop_press_time: float = 0.15
    hop_lift_speed: float = 0.02
    hop_speed: float = 0.01
    hop_settle_time: float = 0.1
    hop_descent_speed: float = 0.003
    hop_rot_stiffness: float = 100.0
    timeouts: tuple[tuple[str, float], ...] = _DEFAULT_TIMEOUTS

    def __post_init__(self) -> None:
        check_positive(
            self, "insertion_depth", "approach_height", "contact_force", "press_force",
            "spiral_pitch", "hop_step", "search_radius", "drop_threshold", "slide_speed",
            "three_point_force", "slide_press_force", "approach_speed", "search_stiffness",
            "insert_stiffness", "wiggle_period", "insert_speed", prefix="assembly.",
        )
        if not 0.0 < self.moment_limit_fraction <= 1.0:
            raise ConfigError("assembly.moment_limit_fraction",
                              f"must lie in (0, 1], got {self.moment_limit_fraction!r}")
        check_non_negative(self, "search_tilt_deg", "wiggle_amplitude_deg",
                      prefix="assembly.")
        check_positive(
            self, "rot_contact_damping", "contact_damping", "rot_compliance_angle_deg",
            "still_time", "align_step_deg", "hop_lift_speed", "hop_speed", "hop_descent_speed",
            "hop_rot_stiffness", prefix="assembly.",
        )
        check_non_negative(
            self, "entry_depth", "settle_time", "length_tolerance", "longer_end_margin",
            "retry_lift",
            "slide_settle_time", "climb_travel", "plane_contact_margin", "hop_height",
            "hop_press_time", "hop_settle_time", prefix="assembly.",
        )
        check_fraction(self, "lost_width_fraction", "three_point_fraction", prefix="assembly.")
        for name, least in (("max_retries", 0), ("max_align_adjustments", 1),
                            ("max_insert_stalls", 0), ("plane_window", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ConfigError(f"assembly.{name}",
                                  f"must be an integer >= {least}, got {value!r}")
        phases = [name for name, _ in _DEFAULT_TIMEOUTS]
        names = [item[0] if isinstance(item, tuple) and len(item) == 2 else item
                 for item in self.timeouts]
        for item, name in zip(self.timeouts, names, strict=True):
            if not (isinstance(item, tuple) and len(item) == 2):
                raise ConfigError("assembly.timeouts", f"expected (phase, seconds) pairs, got "
                                                       f"{item!r}")
            if name not in phases:
                raise ConfigError("assembly.timeouts", f"names no phase {name!r} (every phase "
                                                       f"needs a time-out: {', '.join(phases)})")
            value = item[1]
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not 0 < value <= MAX_PHASE_TIMEOUT_S:
                raise ConfigError(f"assembly.timeouts.{name}", f"must lie in (0, "
                                  f"{MAX_PHASE_TIMEOUT_S:g}] s, got {value!r}")
        if sorted(names) != sorted(phases):
            missing = [p for p in phases if p not in names] or [
                p for p in phases if names.count(p) > 1]
            raise ConfigError("assembly.timeouts", f"every phase needs one time-out "
                                                   f"({', '.join(phases)}); {missing[0]!r} is "
                                                   "missing or repeated")

    def timeout(self, phase: str) -> float:
        return dict(self.timeouts)[phase]
