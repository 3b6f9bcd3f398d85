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

    The per-tick maths is written on Python floats (:mod:`vgs.vecmath`) and MuJoCo's own
    routines (``mju_mulMatTMat``, ``mju_mulMatTVec``, ``mju_cholFactor``, ``mju_cholSolve``),
    never numpy's BLAS products, so that a tick gives the same bits on every CPU.

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
        self._scratch = mujoco.MjData(m)
        # Views and work arrays reused every tick.
        self._qpos = _block(d.qpos, ids.arm_qpos)
        self._ctrl = _block(d.ctrl, ids.arm_act)
        self._sqpos = _block(self._scratch.qpos, ids.arm_qpos)
        self._tcp_xpos = d.site_xpos[ids.tcp_site]
        self._tcp_xmat = d.site_xmat[ids.tcp_site]
        self._ft_xpos = d.site_xpos[ids.ft_site]
        self._ft_xmat = d.site_xmat[ids.ft_site]
        self._s_tcp_xpos = self._scratch.site_xpos[ids.tcp_site]
        self._s_tcp_xmat = self._scratch.site_xmat[ids.tcp_site]
        self._model, self._tcp_site = m, ids.tcp_site
        if ids.ft_torque_adr != ids.ft_force_adr + 3:
            raise ValueError("the F/T force and torque sensors must be adjacent")
        self._raw = d.sensordata[ids.ft_force_adr:ids.ft_force_adr + 6]
        self._jac = np.zeros((6, m.nv))  # rows: translation, rotation
        self._jac_p, self._jac_r = self._jac[:3], self._jac[3:]
        self._J_view = _block(self._jac.T, ids.arm_dof).T  # follows mj_jacSite's output
        self._J = np.zeros((6, 6))  # its contiguous copy, MuJoCo's routines' operand
        self._err = np.zeros(6)
        self._H = np.zeros((6, 6))
        self._g = np.zeros(6)
        self._dq = np.zeros(6)
        self._damp = DLS_LAMBDA**2 * np.eye(6)
        p, R = self.tcp_pose_t()
        self._p_ref: vm.Vec3 = p
        self._R_ref: vm.Mat3 = R
        self.q_cmd = self.joint_positions()
        # Gravity compensation of the payload below the sensor (see tare()).
        self._tool_mass, self._tool_com = tool_inertial(cell)
        self._p_ft_tcp = vm.mtv(vm.mat3(self._ft_xmat),
                                vm.sub(self._tcp_xpos.tolist(), self._ft_xpos.tolist()))
        self.payload_mass = self._tool_mass
        self.payload_com: vm.Vec3 = self._tool_com
        self._g_tare: tuple[float, ...] = (0.0,) * 6
        self._compensate = False

    def set_payload(self, peg_mass: float) -> None:
        """Compensate a held peg of ``peg_mass`` as if its centre of mass lay at the TCP (the
        pads) besides the tool's own load; takes effect at the next :meth:`tare`:
        ``c = (m_tool c_tool + m_peg p_tcp) / (m_tool + m_peg)`` (sensor frame)."""
        m = self._tool_mass + peg_mass
        mt = self._tool_mass
        c, p = self._tool_com, self._p_ft_tcp
        self.payload_com = ((mt * c[0] + peg_mass * p[0]) / m, (mt * c[1] + peg_mass * p[1]) / m,
                            (mt * c[2] + peg_mass * p[2]) / m)
        self.payload_mass = m

    def _gravity_wrench(self) -> tuple[float, float, float, float, float, float]:
        """The payload's weight as an external wrench on the tool, sensor frame:
        ``f = R_world_ft^T (0, 0, -m g)`` (the third row of ``R_world_ft`` times ``-m g``),
        ``tau = c x f``."""
        w = -GRAVITY * self.payload_mass
        zx, zy, zz = self._ft_xmat[6:9].tolist()
        gx, gy, gz = w * zx, w * zy, w * zz
        cx, cy, cz = self.payload_com
        return gx, gy, gz, cy * gz - cz * gy, cz * gx - cx * gz, cx * gy - cy * gx

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
        self._g_tare = self._gravity_wrench()
        self._compensate = True

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

    def read_ft(self) -> np.ndarray:
        """Sample the F/T sensor; update and return the world-frame wrench at the TCP.

        The sensor's wrench, less the change of the payload's weight since the tare
        (``(w - W_g(R)) + W_g(R_tare)``), is turned into the world frame by ``R_world_ft`` and
        moved from the sensor's origin to the TCP: ``tau_tcp = tau_ft + (p_ft - p_tcp) x f``
        (plain floats)."""
        w = self.ft.sample(self._raw)
        if self._compensate:
            g, t = self._gravity_wrench(), self._g_tare
            w = ((w[0] - g[0]) + t[0], (w[1] - g[1]) + t[1], (w[2] - g[2]) + t[2],
                 (w[3] - g[3]) + t[3], (w[4] - g[4]) + t[4], (w[5] - g[5]) + t[5])
        self.wrench_sensor[:] = w
        R_world_ft = tuple(self._ft_xmat.tolist())
        f0, f1, f2 = vm.mv(R_world_ft, w[0:3])
        m0, m1, m2 = vm.mv(R_world_ft, w[3:6])
        x0, x1, x2 = self._ft_xpos.tolist()
        y0, y1, y2 = self._tcp_xpos.tolist()
        r0, r1, r2 = x0 - y0, x1 - y1, x2 - y2
        self.wrench[:] = (f0, f1, f2, m0 + (r1 * f2 - r2 * f1), m1 + (r2 * f0 - r0 * f2),
                          m2 + (r0 * f1 - r1 * f0))
        return self.wrench

    # -- commands ---------------------------------------------------------------------------

    @property
    def p_ref(self) -> np.ndarray:
        """The reference position ``p_world_ref`` [m] (a fresh array)."""
        return np.array(self._p_ref)

    @property
    def R_ref(self) -> np.ndarray:
        """The reference attitude ``R_world_ref`` (a fresh 3x3 array)."""
        return vm.array3(self._R_ref)

    @property
    def reference_t(self) -> tuple[vm.Vec3, vm.Mat3]:
        """The reference pose as plain floats."""
        return self._p_ref, self._R_ref

    def set_reference(self, p: np.ndarray | vm.Vec3, R: np.ndarray | vm.Mat3) -> None:
        """Set the reference pose (arrays, or a 3-tuple and a flat 9-tuple)."""
        self._p_ref = p if isinstance(p, tuple) else vm.vec3(p)
        self._R_ref = R if isinstance(R, tuple) else vm.mat3(R)

    def _commanded_t(self) -> tuple[vm.Vec3, vm.Mat3]:
        """``(p_cmd, R_cmd)``: the reference displaced by the compliant offset,
        ``p_ref + e_p`` and ``exp([e_r]_x) R_ref`` (``R_ref`` itself while ``e_r`` is zero, as
        it is whenever the arm is not compliant)."""
        e0, e1, e2, rx, ry, rz = self.admittance.offset.tolist()
        px, py, pz = self._p_ref
        p = (px + e0, py + e1, pz + e2)
        if rx == 0.0 and ry == 0.0 and rz == 0.0:
            return p, self._R_ref
        return p, vm.mm(vm.exp_so3((rx, ry, rz)), self._R_ref)

    def absorb_offset(self) -> None:
        """Move the compliant offset into the reference (the commanded pose is unchanged)."""
        self._p_ref, self._R_ref = self._commanded_t()
        self.admittance.offset[:] = 0.0
        self.admittance.velocity[:] = 0.0

    def update(self, dt: float) -> None:
        """One control tick: F/T -> admittance -> IK -> joint targets."""
        self.read_ft()
        if self.compliant:
            self.admittance.step(self.wrench, dt)
        (px, py, pz), R_cmd = self._commanded_t()
        m, sd, site = self._model, self._scratch, self._tcp_site
        J, H, g, dq, err = self._J, self._H, self._g, self._dq, self._err
        step_max = MAX_JOINT_SPEED * dt
        q = self.q_cmd
        for k in range(IK_ITERATIONS):
            self._sqpos[:] = q
            mujoco.mj_kinematics(m, sd)
            if k == 0:
                # Jacobian at the first iterate; the later Newton steps reuse it and its
                # factorisation (a chord step: |dq| <= pi dt per joint, so J barely changes).
                mujoco.mj_comPos(m, sd)
                mujoco.mj_jacSite(m, sd, self._jac_p, self._jac_r, site)
                J[:] = self._J_view
                # Damped least squares: dq = (J^T J + lambda^2 I)^-1 J^T err, Cholesky-factored
                # (the matrix is symmetric positive definite); MuJoCo's own products.
                mujoco.mju_mulMatTMat(H, J, J)
                H += self._damp
                mujoco.mju_cholFactor(H, 0.0)
            x, y, z = self._s_tcp_xpos.tolist()
            # Attitude error log(R_cmd R(q)^T).
            rx, ry, rz = vm.log_so3(vm.mmt(R_cmd, tuple(self._s_tcp_xmat.tolist())))
            e = (px - x, py - y, pz - z, rx, ry, rz)
            err[:] = e
            mujoco.mju_mulMatTVec(g, J, err)
            mujoco.mju_cholSolve(dq, H, g)
            steps = dq.tolist()
            if max(steps) > step_max or min(steps) < -step_max:  # clip only where it acts
                np.minimum(dq, step_max, out=dq)
                np.maximum(dq, -step_max, out=dq)
            q += dq
            if max(e) < 1e-7 and min(e) > -1e-7:
                break
        self._ctrl[:] = q


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
