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

The check runs in C (:func:`vgs.native.latch_update`, in :mod:`vgs.vecmath`'s order of
operations, with MuJoCo's ``mj_mulJacTVec``, ``mj_objectVelocity`` and ``mju_mat2Quat``).
Nothing here reads the controller; the latch is part of the cell's physics, like the contacts.
Its state is ground truth (records and tests only).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from vgs import native
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
        self.peg_radius = peg_radius
        self.capacity_per_newton = grasp_moment_capacity(cfg) / (2.0 * cfg.force)
        # Ground truth for records and tests, written by the C latch: the last load (the
        # wrench's place on the limit surface) and how often the pads broke loose.
        self._out = np.zeros(2)
        left, right = (int(g) for g in ids.pad_geoms)
        self._native = native.latch_new(
            model._address, data._address,
            (int(self.eq), int(self.housing), int(self.peg), int(self.tcp), int(self.peg_geom),
             left, right, int(ids.peg_dof)),
            (float(cfg.force), float(cfg.pad_friction), float(peg_radius),
             float(self.capacity_per_newton)),
            (ENGAGE_FRACTION, RELEASE_FRACTION, STICK_SPEED, STICK_RATE, REENGAGE_LOAD),
            self._out)

    @property
    def last_load(self) -> float:
        """The gripper's load on the pads' limit surface at the last check (1: on it; 0 while
        the pads do not pinch)."""
        return float(self._out[0])

    @property
    def breaks(self) -> int:
        """How often the pads broke loose."""
        return int(self._out[1])

    @property
    def stuck(self) -> bool:
        """Whether the pads stick (the weld is active)."""
        return bool(self.data.eq_active[self.eq])

    def update(self) -> None:
        """Check the latch after the physics steps of one control tick (module docstring):

        * nothing touches anything, or the pads do not both press with ``ENGAGE_FRACTION`` of
          the grip while they slip: no pinch, load 0;
        * otherwise the load ``L`` of the pads' contacts' (and, while stuck, the weld's)
          wrench on the limit surface; stuck: let go when ``L > 1`` or the pads press less than
          ``2 RELEASE_FRACTION`` of the grip together; slipping: engage when
          ``L < REENGAGE_LOAD`` and the peg moves relative to the housing slower than
          ``STICK_SPEED`` at the TCP and ``STICK_RATE``.

        On engaging, the weld's relative pose is the present one: MuJoCo's weld holds
        ``p_1 + R_1 relpos = p_2 + R_2 anchor`` and ``q_1 relquat = q_2``, so with the anchor at
        the peg's origin ``relpos = R_1^T (p_2 - p_1)`` and ``relquat = quat(R_1^T R_2)``.
        """
        native.latch_update(self._native)

    def weld_wrench(self) -> tuple[np.ndarray, np.ndarray]:
        """The wrench the weld alone exerts on the peg while the pads stick (zero otherwise): the
        force and the moment about the TCP in the tool frame [N, N m], what the stick state
        carries beyond the pads' contacts (the grasp watch's record).

        The weld's constraint forces ``f`` mapped onto the peg's free joint (``J^T f``) give the
        world-frame force at the peg's origin and the torque ``tau`` in the peg's frame;
        ``m = R_world_peg tau + r x f`` about the TCP (``r = p_peg - p_tcp``); both turned into
        the tool frame by ``R_world_tcp^T``. The latch's load uses the same wrench of the pads'
        contacts' rows and the weld's together, on the ellipsoid of the module docstring.
        """
        f, mom = native.latch_weld_wrench(self._native)
        return np.array(f), np.array(mom)
