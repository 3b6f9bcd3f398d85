"""Static friction of the RG2's pads: the grasp sticks until its load reaches the pads' limit.

MuJoCo's friction is velocity-regularised: a contact that transmits a tangential load slides a
little, all the time. MuJoCo's no-slip post-solver (``sim.noslip_iterations``) pins the pads
while they are the peg's only contacts, but once the peg also presses on the table or a wall of
the hole the peg creeps round in the pads under a third of the grasp's capacity (0.83 deg in
5 s, ``benchmarks/probe_grasp_creep.py`` at ``ac53c96``), and more no-slip iterations make a
step load jump instead (docs/cell.md, "The grasp"). A rubber pad does not creep: it sticks
until the load reaches the Coulomb limit and then slides.

:class:`PadStiction` gives the pads that stick state, as a latch checked once per control tick:

*stick*
    A weld between the gripper housing (body ``rg2``) and the peg, at their relative pose of
    the moment it engaged, carries the load the pads' contacts do not. The contacts keep
    pressing with the grip force and keep their friction; the weld only removes the creep.
*slip*
    The wrench the gripper exerts on the peg (the weld's and the pad contacts'), taken at the
    TCP in the tool frame, is compared with the pads' friction limit surface, an ellipsoid
    through the four friction-limited components (Howe and Cutkosky's ellipsoidal
    approximation of a limit surface)::

        (f_x / (mu N))^2 + (f_z / (mu N))^2 + (m_x / (mu N r))^2 + (m_y / M_y)^2 <= 1

    with N the pads' summed normal force read from their contacts, tool x along the pads'
    long side (the peg's axis), tool y the pinch axis, tool z the approach axis; the pads
    touch the peg at r = its radius from the axis; ``M_y = grasp_moment_capacity * N / (2 F)``
    is the line contacts' torsion (:func:`vgs.sim.rg2.grasp_moment_capacity`). ``f_y`` and
    ``m_z`` are carried by the pads' normal pressure, not by friction. Beyond the surface, or
    with the pads pressing less than ``RELEASE_FRACTION`` of the grip force on average (the
    gripper opening), the weld lets go and the pads slide on MuJoCo's own (kinetic) friction.
*engage*
    Both pads press with at least ``ENGAGE_FRACTION`` of the grip force, the peg moves
    relative to the pads slower than ``STICK_SPEED`` and ``STICK_RATE``, and the contacts'
    own load lies inside ``REENGAGE_LOAD`` of the surface (a peg sliding at the limit does
    not re-stick until its load has dropped).

Nothing here reads the controller; the latch is part of the cell's physics, like the contacts.
Its state is ground truth (records and tests only).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from vgs import vecmath as vm
from vgs.config import GripperConfig
from vgs.sim.rg2 import grasp_moment_capacity

if TYPE_CHECKING:
    from vgs.sim.ids import CellIds

WELD_NAME = "pad_stiction"

ENGAGE_FRACTION = 0.5  # each pad's normal force, of the grip force, for the pads to stick
RELEASE_FRACTION = 0.25  # pads' mean normal force below this, of the grip: the grasp opens
STICK_SPEED = 0.002  # relative speed at the TCP under which the pads stick [m/s]
STICK_RATE = math.radians(2.0)  # relative angular rate under which the pads stick [rad/s]
REENGAGE_LOAD = 0.8  # the contacts' load, of the limit surface, under which they re-stick


def add_pad_weld(spec: mujoco.MjSpec, solref: list[float], solimp: list[float]) -> None:
    """Add the (inactive) weld between the gripper housing and the peg that holds the stick
    state; :class:`PadStiction` sets its relative pose and switches it."""
    eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_WELD, name=WELD_NAME, name1="rg2",
                           name2="peg", objtype=mujoco.mjtObj.mjOBJ_BODY)
    eq.active = False
    eq.solref = solref
    eq.solimp = solimp


class PadStiction:
    """The pads' stick/slip latch on a compiled cell (see the module docstring).

    Args:
        model: The compiled cell.
        data: Its state.
        ids: The cell's named elements (peg, pads, TCP).
        cfg: The gripper (grip force, pad friction, the capacity's geometry).
        peg_radius: Lever of the pads' tangential forces about the peg's axis [m].
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, ids: CellIds,
                 cfg: GripperConfig, peg_radius: float) -> None:
        self.model, self.data, self.cfg = model, data, cfg
        self.eq = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, WELD_NAME)
        self.housing = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "rg2")
        self.peg, self.tcp, self.peg_geom = ids.peg_body, ids.tcp_site, ids.peg_geom
        self.pads = ids.pad_geoms
        # (geom1, geom2) of a contact between the peg and a pad -> 0 (left pad) or 1 (right).
        left, right = (int(g) for g in ids.pad_geoms)
        peg = int(ids.peg_geom)
        self._pad_of = {(peg, left): 0, (left, peg): 0, (peg, right): 1, (right, peg): 1}
        self.peg_dofs = slice(ids.peg_dof, ids.peg_dof + 6)
        self.peg_radius = peg_radius
        self.capacity_per_newton = grasp_moment_capacity(cfg) / (2.0 * cfg.force)
        self._qfrc = np.zeros(model.nv)
        self._weights = np.zeros(0)  # the rows' weights of _selected_wrench
        self._vel = np.zeros(6)
        self._vel_housing = np.zeros(6)
        # Views into the state and work arrays, made once: the latch runs every control tick,
        # where numpy's per-call overhead on 3-vectors costs more than the arithmetic.
        dof = ids.peg_dof
        self._f_peg = self._qfrc[dof:dof + 3]  # J^T f on the peg's free joint: world force
        self._tau_peg_local = self._qfrc[dof + 3:dof + 6]  # and torque, peg frame
        self._R_world_peg = data.xmat[self.peg]  # flat, row-major
        self._p_world_peg = data.xpos[self.peg]
        self._R_world_tcp = data.site_xmat[self.tcp]
        self._p_world_tcp = data.site_xpos[self.tcp]
        # Ground truth for records and tests: how often the pads broke loose, the last load.
        self.breaks = 0
        self.last_load = 0.0

    @property
    def stuck(self) -> bool:
        """Whether the pads stick (the weld is active)."""
        return bool(self.data.eq_active[self.eq])

    def update(self) -> None:
        """Check the latch after the physics steps of one control tick."""
        d, grip = self.data, self.cfg.force
        stuck = bool(d.eq_active[self.eq])
        if not stuck and not d.ncon:
            self.last_load = 0.0  # nothing touches anything: no pinch
            return
        n_left, n_right = self._select_pad_rows()
        if not stuck and min(n_left, n_right) < ENGAGE_FRACTION * grip:
            self.last_load = 0.0  # no pinch: nothing to stick (the grasp's idle ticks)
            return
        load = self._limit_value(*self._selected_wrench(), n_left + n_right)
        self.last_load = load
        if stuck:
            # The pinch, from both pads together: while stuck the weld also carries the pinch,
            # and one pad's contact can drop out of MuJoCo's collision for a step.
            if load > 1.0 or n_left + n_right < 2.0 * RELEASE_FRACTION * grip:
                d.eq_active[self.eq] = 0
                self.breaks += 1
        elif load < REENGAGE_LOAD and self._relative_motion_small():
            self._engage()

    # -- the latch's pieces -----------------------------------------------------------------

    def _engage(self) -> None:
        """Weld the peg to the housing at their present relative pose.

        MuJoCo's weld holds ``p_1 + R_1 relpos = p_2 + R_2 anchor`` and
        ``q_1 relquat = q_2``: with the anchor at the peg's origin, ``relpos`` is the peg's
        position and ``relquat`` its orientation in the housing's frame.
        """
        m, d = self.model, self.data
        p1, R1 = d.xpos[self.housing].tolist(), tuple(d.xmat[self.housing].tolist())
        p2, R2 = d.xpos[self.peg].tolist(), tuple(d.xmat[self.peg].tolist())
        eq = m.eq_data[self.eq]
        eq[0:3] = 0.0
        eq[3:6] = vm.mtv(R1, vm.sub(p2, p1))
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, np.array(vm.mtm(R1, R2)))
        eq[6:10] = q
        eq[10] = 1.0  # torquescale
        d.eq_active[self.eq] = 1

    def _relative_motion_small(self) -> bool:
        """Whether the peg moves relative to the housing slower than the stick thresholds."""
        m, d = self.model, self.data
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, self.peg, self._vel, 0)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, self.housing,
                                 self._vel_housing, 0)
        vel, hsg = self._vel.tolist(), self._vel_housing.tolist()
        w_peg, w_hsg = vel[:3], hsg[:3]
        p_tcp = d.site_xpos[self.tcp].tolist()
        # v = v_origin + w x (p_tcp - p_origin): each body's velocity at the TCP.
        v_peg = vm.add(vel[3:], vm.cross(w_peg, vm.sub(p_tcp, d.xpos[self.peg].tolist())))
        v_hsg = vm.add(hsg[3:], vm.cross(w_hsg, vm.sub(p_tcp, d.xpos[self.housing].tolist())))
        return (vm.norm(vm.sub(v_peg, v_hsg)) < STICK_SPEED
                and vm.norm(vm.sub(w_peg, w_hsg)) < STICK_RATE)

    def weld_wrench(self) -> tuple[np.ndarray, np.ndarray]:
        """The wrench the weld alone exerts on the peg while the pads stick (zero otherwise): the
        force and the moment about the TCP in the tool frame [N, N m], what the stick state
        carries beyond the pads' contacts (the grasp watch's record)."""
        efc_force = self.data.efc_force.tolist()
        weights = [0.0] * len(efc_force)
        self._copy_weld_rows(weights, efc_force)
        self._weights = np.array(weights)
        f, mom = self._selected_wrench()
        return np.array(f), np.array(mom)

    def _copy_weld_rows(self, weights: list[float], efc_force: list[float]) -> None:
        """Copy the weld's constraint forces into ``weights`` (no rows unless the pads
        stick)."""
        ne = self.data.ne  # equality rows come first, each constraint's rows together
        if ne:
            rows = self.data.efc_id[:ne].tolist()
            if self.eq in rows:
                first = rows.index(self.eq)
                last = first + rows.count(self.eq)
                weights[first:last] = efc_force[first:last]

    def _select_pad_rows(self) -> tuple[float, float]:
        """Set the row weights of the gripper's wrench on the peg (the pad contacts' and the
        weld's constraint forces, zero elsewhere) and return the pads' normal forces [N] (with
        elliptic cones a contact's first row is its normal force)."""
        d = self.data
        efc_force = d.efc_force.tolist()
        weights = [0.0] * len(efc_force)
        n_left = n_right = 0.0
        ncon = d.ncon
        if ncon:
            # Plain Python over the few contacts: per tick, numpy's per-call overhead on arrays
            # this small costs more than the loop (this method runs once per control tick).
            con = d.contact
            geoms = con.geom.ravel().tolist()
            addresses = con.efc_address.tolist()
            dims = con.dim.tolist()
            pad_of = self._pad_of
            for i in range(ncon):
                side = pad_of.get((geoms[2 * i], geoms[2 * i + 1]))
                a = addresses[i]
                if side is None or a < 0:
                    continue
                n = dims[i]
                weights[a:a + n] = efc_force[a:a + n]
                if side == 0:
                    n_left += efc_force[a]
                else:
                    n_right += efc_force[a]
        self._copy_weld_rows(weights, efc_force)
        self._weights = np.array(weights)
        return n_left, n_right

    def _selected_wrench(self) -> tuple[list[float], list[float]]:
        """Force and moment about the TCP, tool frame, of the rows :meth:`_select_pad_rows`
        weighted: their constraint forces mapped onto the peg's free joint (``J^T f``), the
        world-frame force ``f`` at the peg's origin and the torque ``tau`` in the peg's
        frame; ``m = R_world_peg tau + r x f`` about the TCP, ``r = p_peg - p_tcp``; both
        turned into the tool frame by ``R_world_tcp^T`` (plain floats, :mod:`vgs.vecmath`)."""
        mujoco.mj_mulJacTVec(self.model, self.data, self._qfrc, self._weights)
        f = tuple(self._f_peg.tolist())
        t0, t1, t2 = vm.mv(tuple(self._R_world_peg.tolist()), self._tau_peg_local.tolist())
        f0, f1, f2 = f
        p0, p1, p2 = self._p_world_peg.tolist()
        c0, c1, c2 = self._p_world_tcp.tolist()
        r0, r1, r2 = p0 - c0, p1 - c1, p2 - c2
        mom = (t0 + (r1 * f2 - r2 * f1), t1 + (r2 * f0 - r0 * f2), t2 + (r0 * f1 - r1 * f0))
        R_world_tcp = tuple(self._R_world_tcp.tolist())
        return list(vm.mtv(R_world_tcp, f)), list(vm.mtv(R_world_tcp, mom))

    def _limit_value(self, f: list[float], mom: list[float], normal: float) -> float:
        """The tool-frame wrench's place on the pads' ellipsoidal limit surface: 1 on it."""
        if normal <= 0.0:
            return math.inf
        mu_n = self.cfg.pad_friction * normal
        m_y = self.capacity_per_newton * normal
        return math.sqrt((f[0] / mu_n) ** 2 + (f[2] / mu_n) ** 2
                         + (mom[0] / (mu_n * self.peg_radius)) ** 2 + (mom[1] / m_y) ** 2)
