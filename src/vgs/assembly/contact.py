"""The contact phases of the assembly (search, slide, align, insert) and the compliance they
share: the admittance in contact, the peg's estimated axis and lower end, the measured moments
and the grasp watch. :class:`ContactPhases` is a base of
:class:`vgs.assembly.strategy.AssemblyModule`, whose docstring states every phase; the
exceptions of the strategy live here. Every tunable is a field of
:class:`vgs.config.AssemblyConfig` (``self.cfg``).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from vgs import vecmath as vm
from vgs.assembly.spiral import GOLDEN_ANGLE, spiral_points


class Recovery(Exception):
    """The contact state the controller believed in was wrong: lift and search again."""


class PhaseTimeout(Exception):
    """A phase ran past its timeout (or, ``cutoff``, the assembly past its time limit)."""

    def __init__(self, phase: str, cutoff: bool = False) -> None:
        super().__init__(phase)
        self.phase, self.cutoff = phase, cutoff


class PegLost(Exception):
    """The grasp watch saw the peg leave the pads (finger width or weight)."""


class ContactPhases:
    """The contact phases and their compliance helpers; the rest of the state machine (the
    attributes these methods read, the phase clock ``_begin``/``_end``/``_check_timeout``) is
    :class:`vgs.assembly.strategy.AssemblyModule`'s."""

    def _check_grasp(self) -> None:
        """Raise :class:`PegLost` when the fingers have closed past the peg (its nominal
        diameter less a tolerance): the RG2's width reading, the robot's own signal."""
        if self.robot.gripper.width() < self.cfg.lost_width_fraction * self.peg.diameter:
            raise PegLost

    def _check_weight(self) -> None:
        """In free air after the tare at the upright pose: a peg that fell out shows as an
        upward force of its weight on the tared sensor."""
        if self.robot.arm.wrench[2] > 0.5 * self.estimate.weight:
            raise PegLost

    def _lowest_rim_offset(self, R_tcp: np.ndarray) -> np.ndarray:
        """Vector from the lower face's centre to its lowest rim point for tool attitude R."""
        axis = vm.scale(self.estimate.down_sign, vm.column(vm.mat3(R_tcp), 0))
        # v = down - (down . a) a with down = (0, 0, -1): the down direction across the axis.
        v = vm.sub((0.0, 0.0, -1.0), vm.scale(-axis[2], axis))
        n = vm.norm(v)
        return np.zeros(3) if n < 1e-9 else np.array(vm.scale(self.peg.radius / n, v))

    def _moment(self) -> float:
        """Measured moment about the pinch axis at the TCP (the pads) [N m]."""
        _, _, _, m0, m1, m2 = self.robot.arm.wrench.tolist()
        a0, a1, a2 = self._tilt_axis_t
        return m0 * a0 + m1 * a1 + m2 * a2

    def _comply(self, lateral: float, lateral_damping: float | None = None,
                z_damping: float | None = None,
                k_rot: float | None = None) -> None:
        """Admittance in contact.

        Stiffness ``lateral`` in x and y, force control in z, and a rotational stiffness that
        keeps the moment on the grasp below its capacity: a reference that runs
        ``rot_compliance_angle_deg`` ahead of a jammed peg loads the pads with ``moment_limit``
        (assembly.moment_limit_fraction of the grasp's capacity); ``k_rot`` overrides it.

        Damping: a contact is a spring k_c on the peg; the discrete admittance loop at the
        control period dt stays stable for D > k_c dt on every axis the contact loads
        (the rule of :mod:`vgs.control.admittance`). Translation: at least
        ``contact_damping`` laterally (``lateral_damping`` where larger: it sets the speed of a
        force-controlled slide) and ``controller.force_damping`` in z (``z_damping`` where
        larger). Rotation: the lower end in contact is a lateral spring at the lever h below
        the pads, a rotational stiffness k_c h^2 about them (about 250 N m/rad for MuJoCo's
        4 ms contacts on a 0.55 kg peg at h = 85 mm), so D >= ``rot_contact_damping``.
        """
        if k_rot is None:
            k_rot = self.moment_limit / math.radians(self.cfg.rot_compliance_angle_deg)
        d_lat = max(self.cfg.contact_damping, lateral_damping or 0.0)
        d_z = max(self.robot.cfg.force_damping, z_damping or 0.0)
        d_rot = self.cfg.rot_contact_damping
        self.robot.arm.admittance.set_stiffness(
            np.array([lateral, lateral, 0.0, k_rot, k_rot, k_rot]),
            damping=np.array([d_lat, d_lat, d_z, d_rot, d_rot, d_rot]))

    def _watch(self) -> None:
        """Per-tick checks in contact: the finger width, and the peak measured moment."""
        m = abs(self._moment())
        if m > self.peak_moment:
            self.peak_moment = m
        self._check_grasp()

    def search(self) -> None:
        """Archimedes spiral of touch-downs: the lowest rim point is lifted, carried in free
        air to the next point of the spiral around the nominal hole and lowered until the
        contact force reaches ``contact_force``; pressed with ``press_force``, the TCP height
        below the plane's (the approach's plane contact, or the highest of the last
        ``plane_window`` touch-downs where they landed higher) is the rim point's depth. Deeper than
        ``drop_threshold``: two-point contact (Figure 2b). Nothing rubs, so no friction turns
        the peg in the pads."""
        robot, cfg = self.robot, self.cfg
        # The approach ended in plane contact with the rim point on the surface: depths are
        # measured from there, or from the highest of the last plane_window touch-downs where
        # the peg's turn in the pads has raised the plane's TCP height since (a new search
        # starts afresh: the peg may have turned).
        z_contact = robot.arm.tcp_height()
        self.z_plane = z_contact
        heights: deque[float] = deque(maxlen=cfg.plane_window)
        # Every new search starts at the centre again, its spiral turned by the golden angle:
        # the hole is likeliest near the nominal centre, and the points of the last spiral led
        # to a wrong contact state.
        self.R_search = robot.arm.R_ref.copy()
        low = self.low_rim_from_tcp[:2]
        for target in spiral_points(self.nominal_hole_xy, cfg.spiral_pitch, cfg.hop_step,
                                    cfg.search_radius, turn=self.retries * GOLDEN_ANGLE):
            z = self._touch_down(target - low)
            if self.z_plane - z > cfg.drop_threshold:
                return
            if z - self.z_plane <= 0.5 * cfg.drop_threshold:  # not on something higher
                heights.append(z)
                self.z_plane = max(z_contact, *heights)
            self._check_timeout("search")

    def _touch_down(self, tcp_xy: np.ndarray) -> float:
        """Lift, carry the TCP to ``tcp_xy`` in free air, lower it to contact, press; return
        the TCP height [m] (the robot's own joint state)."""
        robot, cfg = self.robot, self.cfg
        adm = robot.arm.admittance
        robot.arm.set_compliant(False)
        p = robot.arm.p_ref.copy()
        # Up from where the TCP is (never down into the surface), at least to the plane's.
        p[2] = max(robot.arm.tcp_height(), p[2], self.z_plane) + cfg.hop_height
        # Back to the search attitude: what the compliance gave way to at the last
        # touch-down must not accumulate.
        robot.move_to(p, self.R_search, speed=cfg.hop_lift_speed, settle=0.0)
        self._watch()
        p[:2] = tcp_xy
        robot.move_to(p, self.R_search, speed=cfg.hop_speed, settle=cfg.hop_settle_time)
        self._watch()
        robot.arm.set_compliant(True)
        self._comply(0.0, k_rot=cfg.hop_rot_stiffness)
        adm.wrench_des[:] = 0.0
        adm.wrench_des[2] = -adm.damping[2] * cfg.hop_descent_speed
        while robot.arm.wrench[2] < cfg.contact_force:
            robot.tick()
            self._watch()
            self._check_timeout("search")
        adm.wrench_des[2] = -cfg.press_force
        n = max(1, int(round(cfg.hop_press_time / robot.dt)))
        for _ in range(n):
            robot.tick()
            self._watch()
        return robot.arm.tcp_height()

    def slide(self) -> None:
        """Two-point contact (Fig. 2b, 3a): the lowest rim point is in the hole, the lower face
        rests on the rim. Pressing lightly with free lateral axes, a lateral bias along the
        tilt plane, lowest rim point leading, slides the peg until the rim point meets the
        wall; there the tilted face lies over the hole and the peg falls in: three-point
        contact (Fig. 2c). Come to rest with the face across the rim (the wall met off the
        tilt plane, where friction holds the rim point), the slide follows the wall: the bias
        turned 45 deg to one side and then to the other slides the rim point along it."""
        robot, cfg = self.robot, self.cfg
        adm = robot.arm.admittance
        robot.arm.absorb_offset()
        lead = self.low_rim_from_tcp[:2] / max(vm.norm(self.low_rim_from_tcp[:2].tolist()), 1e-9)
        # Lateral damping for a free sliding speed of slide_speed under the bias.
        self._comply(0.0, lateral_damping=cfg.three_point_force / cfg.slide_speed)
        # Settle onto the rim under the light press before the bias.
        adm.wrench_des[:] = [0.0, 0.0, -cfg.slide_press_force, 0.0, 0.0, 0.0]
        for _ in range(max(1, int(round(cfg.slide_settle_time / robot.dt)))):
            robot.tick()
            self._watch()
        self.slide_start = robot.arm.tcp_pose()[0][:2]
        perp = np.array([-lead[1], lead[0]])
        for side in (0.0, 1.0, -1.0):
            if self._slide_to_rest(lead + side * perp):
                return
        raise Recovery  # the lower face did not fall in anywhere along the wall

    def _slide_to_rest(self, direction: np.ndarray) -> bool:
        """Slide with a lateral bias of ``three_point_force`` along ``direction`` (pressing
        with ``slide_press_force``) until the TCP stands still; return whether it came to rest
        fallen into the hole: three-point contact (Figure 2c) from the robot's own state, the
        TCP still (the lateral force the sensor measures then balances the bias) and
        ``_three_point_depth`` below the plane contact."""
        robot, cfg = self.robot, self.cfg
        adm = robot.arm.admittance
        direction = direction / vm.norm(direction.tolist())
        adm.wrench_des[:] = [*(cfg.three_point_force * direction), -cfg.slide_press_force,
                             0.0, 0.0, 0.0]
        window = max(1, int(round(cfg.still_time / robot.dt)))
        last = robot.arm.tcp_pose()[0][:2]
        z_low, xy_low = robot.arm.tcp_height(), last
        n = 0
        while True:
            robot.tick()
            self._watch()
            n += 1
            xy, z = robot.arm.tcp_pose()[0][:2], robot.arm.tcp_height()
            # The rim point cannot travel further than across the hole, nor climb back onto
            # the surface, while it is in the hole: the wrong contact state.
            if (vm.norm((xy - self.slide_start).tolist()) > self.peg.diameter
                    or z > self.z_plane + cfg.drop_threshold):
                raise Recovery
            if z < z_low:
                z_low, xy_low = z, xy
            elif (z > z_low + 0.5 * max(self.z_plane - z_low, 2 * cfg.drop_threshold)
                    and vm.norm((xy - xy_low).tolist()) > cfg.climb_travel):
                # Climbing the far edge: the lower face crossed the hole beside its centre,
                # too shallow for the wall to stop the rim point. Back to where it lay
                # deepest, to go on across the lead.
                adm.wrench_des[:2] = 0.0
                robot.move_to(robot.arm.p_ref + np.array([*(xy_low - xy), 0.0]),
                              robot.arm.R_ref, speed=cfg.slide_speed, settle=0.0)
                return False
            if n % window == 0:
                moving = vm.norm((xy - last).tolist()) > 0.25 * cfg.slide_speed * cfg.still_time
                last = xy
                if not moving:
                    self.z_three = robot.arm.tcp_height()
                    return self.z_three < self.z_plane - self._three_point_depth()
            self._check_timeout("slide")

    def _three_point_depth(self) -> float:
        """Least descent below the plane contact that three-point contact implies [m]: the
        tilted lower face inside the hole, its lowest rim point against the far wall, the
        opposite rim at the top edge lies ``D sin(tilt)`` (3.1 mm for the nominal 30 mm peg at
        6 deg) below the plane contact. ``assembly.three_point_fraction`` of it (half): a face
        across the rim 3 mm beside the hole's axis rests 1.3 mm low, a face over the hole
        2.2-2.7 mm."""
        tilt = math.radians(self.cfg.search_tilt_deg)
        return self.cfg.three_point_fraction * self.peg.diameter * math.sin(tilt)

    def align(self) -> None:
        """Wiggle alignment (Fig. 3c): each adjustment turns the peg back towards upright about
        its estimated lower end and superposes one wiggle, each limited in moment: a rotation
        stops early when the measured moment about the pinch axis reaches the moment limit."""
        robot, cfg = self.robot, self.cfg
        adm = robot.arm.admittance
        amp = math.radians(cfg.wiggle_amplitude_deg)
        align_step = math.radians(cfg.align_step_deg)
        # Lateral force control without bias: the hole guides the peg; press down only. Inside
        # the hole the peg touches both walls: a lateral contact far stiffer than the rim on
        # the face, and at contact_damping the discrete loop chattered between the walls
        # (+-8 N at 14 Hz, wedging a peg tilted 4-5 deg 12 mm deep). The alignment damps its
        # lateral axes like the force-controlled z axis (controller.force_damping).
        robot.arm.absorb_offset()
        adm.wrench_des[:] = [0.0, 0.0, -cfg.press_force, 0.0, 0.0, 0.0]
        self._comply(0.0, lateral_damping=robot.cfg.force_damping)
        n_wiggle = max(2, int(round(cfg.wiggle_period / robot.dt)))
        start_adjustments = self.adjustments
        while True:
            if self.adjustments - start_adjustments >= cfg.max_align_adjustments:
                raise Recovery
            robot.arm.absorb_offset()
            # Rotate back towards upright, at most align_step_deg per adjustment.
            step = max(-align_step, min(align_step, -self._tilt(robot.arm.R_ref)))
            self._rotate_about_tip(step, n_wiggle // 2)
            # One wiggle: +amp, -amp, back, about the estimated lower end.
            for sgn in (1.0, -2.0, 1.0):
                self._rotate_about_tip(sgn * amp, n_wiggle // 4)
            self.adjustments += 1
            z = robot.arm.tcp_pose()[0][2]
            # Aligned (paper eq. 1): the tool's tilt, from the measured joint angles, is under
            # delta, the peg has slid into the hole and the contact moment has relaxed.
            if (z < self.z_three - cfg.entry_depth and abs(self._moment()) < self.aligned_moment
                    and abs(self._tilt(robot.arm.tcp_pose()[1])) < self.delta):
                return
            self._check_timeout("align")

    def _tilt(self, R_world_tcp: np.ndarray) -> float:
        """Signed angle from vertical, about the tilt axis, of the peg axis of tool attitude
        ``R_world_tcp`` (the peg's turn in the pads is not in it)."""
        down = vm.scale(self.estimate.down_sign, vm.column(vm.mat3(R_world_tcp), 0))
        return math.atan2(vm.dot(vm.cross((0.0, 0.0, -1.0), down), self._tilt_axis_t),
                          -down[2])

    def _rotate_about_tip(self, angle: float, n_ticks: int) -> None:
        """Turn the reference by ``angle`` about the pinch axis around the estimated lower end
        (smoothstep profile); stop where the measured moment opposes the turn beyond the
        moment limit (the rotation would only load the grasp)."""
        robot = self.robot
        p0, R0 = robot.arm.reference_t
        # tip = p0 + h s x0 (x0 the tool's x axis, s the down sign): the estimated lower end.
        reach = self.estimate.hanging * self.estimate.down_sign
        tip = vm.add(p0, vm.scale(reach, vm.column(R0, 0)))
        n = max(1, n_ticks)
        sign = 1.0 if angle >= 0 else -1.0
        tip_to_tcp = vm.sub(p0, tip)
        a0, a1, a2 = self._tilt_axis_t
        for k in range(1, n + 1):
            s = k / n
            s = s * s * (3 - 2 * s)
            turn = s * angle
            Rk = vm.exp_so3((turn * a0, turn * a1, turn * a2))
            robot.arm.set_reference(vm.add(tip, vm.mv(Rk, tip_to_tcp)), vm.mm(Rk, R0))
            robot.tick()
            self._watch()
            if -sign * self._moment() > self.moment_limit:
                return

    def insert(self) -> None:
        robot, cfg = self.robot, self.cfg
        adm = robot.arm.admittance
        robot.arm.absorb_offset()
        adm.wrench_des[:] = [0.0, 0.0, -cfg.press_force, 0.0, 0.0, 0.0]
        # Compliance in the lateral axes and force control in rotation (K = 0: the offset turns
        # at M / rot_contact_damping until the walls' moment vanishes) let the hole guide the
        # peg, also where it leans across the pinch axis, which the wiggle does not turn: a
        # grasp whose jaws lay phi off the peg's axis holds it so (the pads lock that angle in).
        # With the stiffness of the other phases the lean stayed above delta and the insertion
        # jammed from phi = 5 deg (docs/training.md, "The jaw angle").
        self._comply(cfg.insert_stiffness, k_rot=0.0)
        z_target = self.z_contact - self.cfg.insertion_depth - 0.003
        last_z = robot.arm.tcp_pose()[0][2]
        n_wiggle = max(2, int(round(cfg.wiggle_period / robot.dt)))
        amp = math.radians(cfg.wiggle_amplitude_deg)
        stalls = 0
        check = max(1, int(round(0.25 / robot.dt)))
        while robot.arm.tcp_pose()[0][2] > z_target:
            for _ in range(check):
                robot.tick()
                self._watch()
            z = robot.arm.tcp_pose()[0][2]
            if last_z - z < 0.25 * cfg.insert_speed * 0.25 * check * robot.dt / 0.25:
                # Stalled (jammed): one more wiggle adjustment; several in a row mean the peg
                # is not in the hole at all (a wrong contact-state decision).
                stalls += 1
                if stalls > cfg.max_insert_stalls:
                    raise Recovery
                for sgn in (1.0, -2.0, 1.0):
                    self._rotate_about_tip(sgn * amp, n_wiggle // 4)
                self.adjustments += 1
            else:
                stalls = 0
            last_z = z
            self._check_timeout("insert")
        self._check_grasp()
