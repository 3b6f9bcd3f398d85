"""The arm controller: reference trajectory + admittance offset -> joint servo targets.

Each control tick (period ``sim.timestep * sim.control_decimation``):

1. read the F/T sensor and express the tared wrench at the TCP in the world frame:
   ``f_w = R_world_ft f_ft``, ``tau_w = R_world_ft tau_ft + (p_ft - p_tcp) x f_w``;
2. advance the admittance offset ``e`` (see :mod:`vgs.control.admittance`);
3. commanded pose ``p_cmd = p_ref + e_p``, ``R_cmd = exp([e_r]_x) R_ref``;
4. differential IK on the *commanded* joint vector (the robot's kinematic model evaluated on a
   scratch ``MjData``, independent of servo lag) with damped least squares:
   ``q_cmd <- q_cmd + (J^T J + lambda^2 I)^-1 J^T [p_cmd - p(q_cmd); log(R_cmd R(q_cmd)^T)]``
   (two steps per tick; the second reuses the first step's Jacobian),
   ``J`` the 6x6 TCP Jacobian of the arm joints at ``q_cmd`` (MuJoCo ``mj_jacSite``), each step
   clipped to the UR5's joint speed;
5. the UR5's joint position servos (MuJoCo position actuators with stiffness ``joint_kp`` and
   implicit damping ``joint_kv``) track ``q_target``.

Only the robot's own state (joint angles through its kinematic model, the F/T signal) enters.
"""

from __future__ import annotations

import mujoco
import numpy as np

from vgs import native
from vgs import vecmath as vm
from vgs.config import ControllerConfig
from vgs.control.admittance import Admittance
from vgs.sim.cell import Cell
from vgs.sim.ft_sensor import FTSensor

GRAVITY = 9.81
DLS_LAMBDA = 0.01
IK_ITERATIONS = 2
# UR5 joint speed limit (datasheet: 180 deg/s on every joint).
MAX_JOINT_SPEED = np.pi


class ArmController:
    """Cartesian admittance control of the UR5 through its joint servos.

    A tick (:meth:`update`) runs in C (:func:`vgs.native.arm_update`): the formulas of this
    module's docstring in :mod:`vgs.vecmath`'s order of operations and MuJoCo's own routines
    (``mj_kinematics``, ``mj_jacSite``, ``mju_mulMatTMat``, ``mju_mulMatTVec``,
    ``mju_cholFactor``, ``mju_cholSolve``), never numpy's BLAS products, so that a tick gives
    the same bits on every CPU. Its state lives in this object's numpy arrays, which the C reads
    and writes in place.

    Args:
        cell: The simulated cell (the controller touches only joint state, actuators and the
            F/T sensor).
        cfg: Controller configuration.
        ft: The wrist F/T sensor model.
    """

    def __init__(self, cell: Cell, cfg: ControllerConfig, ft: FTSensor) -> None:
        self.cell = cell
        self.cfg = cfg
        self.ft = ft
        self.admittance = Admittance(cfg)
        m, d, ids = cell.model, cell.data, cell.ids
        self.wrench = np.zeros(6)  # tared external wrench at the TCP, world frame
        self.wrench_sensor = np.zeros(6)  # tared external wrench, sensor frame
        self.compliant = False  # False: the F/T signal does not drive the admittance
        self._scratch = mujoco.MjData(m)  # the IK's kinematic model, on the commanded joints
        self._qpos = _block(d.qpos, ids.arm_qpos)
        self._tcp_xpos = d.site_xpos[ids.tcp_site]
        self._tcp_xmat = d.site_xmat[ids.tcp_site]
        self._ft_xpos = d.site_xpos[ids.ft_site]
        self._ft_xmat = d.site_xmat[ids.ft_site]
        if ids.ft_torque_adr != ids.ft_force_adr + 3:
            raise ValueError("the F/T force and torque sensors must be adjacent")
        # The reference pose (p_world_ref, then R_world_ref flat, row-major).
        self._ref = np.zeros(12)
        self._ref[:3], self._ref[3:] = self._tcp_xpos, self._tcp_xmat
        self.q_cmd = self.joint_positions()
        # Gravity compensation of the payload below the sensor (see tare()): its mass, centre
        # of mass (sensor frame), whether it is compensated (0/1) and the weight wrench at the
        # tare, W_g(R_tare).
        self._tool_mass, self._tool_com = tool_inertial(cell)
        self._p_ft_tcp = vm.mtv(vm.mat3(self._ft_xmat),
                                vm.sub(self._tcp_xpos.tolist(), self._ft_xpos.tolist()))
        self._payload = np.zeros(11)
        self._payload[0], self._payload[1:4] = self._tool_mass, self._tool_com
        adm, ft = self.admittance, self.ft
        arm_dof, arm_act = _block(np.arange(m.nv), ids.arm_dof), _block(np.arange(m.nu),
                                                                      ids.arm_act)
        self._native = native.arm_new(
            m._address, d._address, self._scratch._address,
            (int(ids.tcp_site), int(ids.ft_site), int(ids.arm_qpos[0]), int(arm_act[0]),
             int(arm_dof[0]), int(ids.ft_force_adr), IK_ITERATIONS),
            (DLS_LAMBDA**2, MAX_JOINT_SPEED, GRAVITY),
            (self._ref, adm.offset, adm.velocity, adm.wrench_des, adm.stiffness, adm.damping,
             adm.mass, adm.vmax, ft.filtered, ft.tare_offset, self._payload, self.wrench,
             self.wrench_sensor, self.q_cmd, ft.noise, ft.state))

    @property
    def payload_mass(self) -> float:
        """Mass compensated below the sensor [kg] (tool, and a held peg after set_payload)."""
        return float(self._payload[0])

    @property
    def payload_com(self) -> vm.Vec3:
        """Its centre of mass in the sensor frame [m]."""
        return vm.vec3(self._payload[1:4])

    def set_payload(self, peg_mass: float) -> None:
        """Compensate a held peg of ``peg_mass`` as if its centre of mass lay at the TCP (the
        pads) besides the tool's own load; takes effect at the next :meth:`tare`:
        ``c = (m_tool c_tool + m_peg p_tcp) / (m_tool + m_peg)`` (sensor frame)."""
        m = self._tool_mass + peg_mass
        mt = self._tool_mass
        c, p = self._tool_com, self._p_ft_tcp
        self._payload[1:4] = ((mt * c[0] + peg_mass * p[0]) / m,
                              (mt * c[1] + peg_mass * p[1]) / m, (mt * c[2] + peg_mass * p[2]) / m)
        self._payload[0] = m

    def gravity_wrench(self) -> tuple[float, float, float, float, float, float]:
        """The payload's weight as an external wrench on the tool, sensor frame:
        ``f = R_world_ft^T (0, 0, -m g)`` (the third row of ``R_world_ft`` times ``-m g``),
        ``tau = c x f`` (in C, as the tick compensates it)."""
        return native.arm_gravity_wrench(self._native)

    def tare(self) -> None:
        """Zero the F/T sensor here and compensate the payload's weight from now on.

        The sensor reads the external wrench relative to the tare; turning the wrist turns the
        payload's weight in the sensor frame, so the change of the expected weight wrench
        ``W_g(R) - W_g(R_tare)`` (tool: its design mass and centre of mass; a held peg: its
        nominal mass at the pads, :meth:`set_payload`) is removed from every later reading.
        A peg held off its centre of mass leaves its gravitational moment
        ``m g c sin(tilt)`` in the signal (paper eq. 2): the controller cannot tell it from a
        contact moment.
        """
        self.ft.tare()
        self._payload[5:11] = self.gravity_wrench()
        self._payload[4] = 1.0

    def set_compliant(self, on: bool) -> None:
        """Let the F/T signal drive the admittance (True) or hold the reference stiffly."""
        if not on:
            self.absorb_offset()
        self.compliant = on

    # -- state from the robot's own sensors ----------------------------------------------

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(p_world_tcp, R_world_tcp)`` from the measured joint angles."""
        return self._tcp_xpos.copy(), self._tcp_xmat.reshape(3, 3).copy()

    def tcp_pose_t(self) -> tuple[vm.Vec3, vm.Mat3]:
        """:meth:`tcp_pose` as plain floats (a 3-tuple and a flat row-major 9-tuple)."""
        return tuple(self._tcp_xpos.tolist()), tuple(self._tcp_xmat.tolist())  # type: ignore

    def tcp_height(self) -> float:
        """Height of the TCP from the measured joint angles [m] (no copies)."""
        return float(self._tcp_xpos[2])

    def joint_positions(self) -> np.ndarray:
        return self._qpos.copy()

    # -- commands ---------------------------------------------------------------------------

    @property
    def p_ref(self) -> np.ndarray:
        """The reference position ``p_world_ref`` [m] (a fresh array)."""
        return self._ref[:3].copy()

    @property
    def R_ref(self) -> np.ndarray:
        """The reference attitude ``R_world_ref`` (a fresh 3x3 array)."""
        return self._ref[3:].reshape(3, 3).copy()

    @property
    def reference_t(self) -> tuple[vm.Vec3, vm.Mat3]:
        """The reference pose as plain floats."""
        ref = self._ref.tolist()
        return tuple(ref[:3]), tuple(ref[3:])  # type: ignore[return-value]

    def set_reference(self, p: np.ndarray | vm.Vec3, R: np.ndarray | vm.Mat3) -> None:
        """Set the reference pose (arrays, or a 3-tuple and a flat 9-tuple)."""
        self._ref[:3] = p
        self._ref[3:] = R if isinstance(R, tuple) else np.ravel(R)

    def commanded_t(self) -> tuple[vm.Vec3, vm.Mat3]:
        """``(p_cmd, R_cmd)``: the reference displaced by the compliant offset,
        ``p_ref + e_p`` and ``exp([e_r]_x) R_ref`` (``R_ref`` itself while ``e_r`` is zero, as
        it is whenever the arm is not compliant), as plain floats (the C tick's own)."""
        return native.arm_commanded(self._native)

    def absorb_offset(self) -> None:
        """Move the compliant offset into the reference (the commanded pose is unchanged)."""
        p, R = self.commanded_t()
        self._ref[:3], self._ref[3:] = p, R
        self.admittance.offset[:] = 0.0
        self.admittance.velocity[:] = 0.0

    def update(self, dt: float) -> None:
        """One control tick: F/T -> admittance -> IK -> joint targets (module docstring), in C:
        the sensor's sample, the payload's compensation and the wrench at the TCP
        (:attr:`wrench`, :attr:`wrench_sensor`), the admittance step while :attr:`compliant`,
        ``IK_ITERATIONS`` damped least-squares steps from :attr:`q_cmd` on the scratch data
        (the Jacobian and its Cholesky factor from the first), each clipped to
        ``MAX_JOINT_SPEED dt`` per joint, stopping early once every error component is under
        1e-7; then the servo targets."""
        native.arm_update(self._native, dt, self.ft.next_row(), self.compliant)


def tool_inertial(cell: Cell) -> tuple[float, vm.Vec3]:
    """Mass and centre of mass (sensor frame) of everything below the F/T sensor's site: the
    robot's own tool (sensor body, RG2), its design data (the gripper's fingers move
    symmetrically, so the centre does not depend on the opening)."""
    m, ids = cell.model, cell.ids
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    body = int(m.site_bodyid[ids.ft_site])
    mass = float(m.body_subtreemass[body])
    com_world = d.subtree_com[body]
    R = vm.mat3(d.site_xmat[ids.ft_site])
    return mass, vm.mtv(R, vm.sub(com_world.tolist(), d.site_xpos[ids.ft_site].tolist()))


def _block(array: np.ndarray, index: np.ndarray) -> np.ndarray:
    """The view ``array[i0:i0 + n]`` for ``index = i0 .. i0 + n - 1`` (the cell builds the arm's
    joints and actuators as contiguous runs)."""
    i0 = int(index[0])
    if not np.array_equal(index, np.arange(i0, i0 + len(index))):
        raise ValueError("the arm's joints and actuators must be numbered contiguously")
    return array[i0:i0 + len(index)]
