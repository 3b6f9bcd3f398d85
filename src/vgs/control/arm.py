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

from vgs.config import ControllerConfig
from vgs.control.admittance import Admittance
from vgs.control.transforms import exp_so3, log_so3_tuple
from vgs.sim.cell import Cell
from vgs.sim.ft_sensor import FTSensor

GRAVITY = 9.81
DLS_LAMBDA = 0.01
IK_ITERATIONS = 2
# UR5 joint speed limit (datasheet: 180 deg/s on every joint).
MAX_JOINT_SPEED = np.pi


class ArmController:
    """Cartesian admittance control of the UR5 through its joint servos.

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
        self._wrench_f, self._wrench_m = self.wrench[:3], self.wrench[3:]
        self.wrench_sensor = np.zeros(6)  # tared external wrench, sensor frame
        self._sensor_f, self._sensor_m = self.wrench_sensor[:3], self.wrench_sensor[3:]
        self.compliant = False  # False: the F/T signal does not drive the admittance
        self._scratch = mujoco.MjData(m)
        # Views and work arrays reused every tick (numpy's per-call overhead dominates on
        # 6-vectors; fancy indexing and fresh arrays would cost more than the arithmetic).
        self._qpos = _block(d.qpos, ids.arm_qpos)
        self._ctrl = _block(d.ctrl, ids.arm_act)
        self._sqpos = _block(self._scratch.qpos, ids.arm_qpos)
        self._tcp_xpos = d.site_xpos[ids.tcp_site]
        self._tcp_xmat = d.site_xmat[ids.tcp_site].reshape(3, 3)
        self._ft_xpos = d.site_xpos[ids.ft_site]
        self._ft_xmat = d.site_xmat[ids.ft_site].reshape(3, 3)
        self._s_tcp_xpos = self._scratch.site_xpos[ids.tcp_site]
        self._s_R_tcp_world = self._scratch.site_xmat[ids.tcp_site].reshape(3, 3).T
        self._model, self._tcp_site = m, ids.tcp_site
        if ids.ft_torque_adr != ids.ft_force_adr + 3:
            raise ValueError("the F/T force and torque sensors must be adjacent")
        self._raw = d.sensordata[ids.ft_force_adr:ids.ft_force_adr + 6]
        self._z_world_in_ft = self._ft_xmat[2]  # third row of R_world_ft: world z, ft frame
        self._jac = np.zeros((6, m.nv))  # rows: translation, rotation
        self._jac_p, self._jac_r = self._jac[:3], self._jac[3:]
        self._J = _block(self._jac.T, ids.arm_dof).T  # a view: follows mj_jacSite's output
        self._JT = self._J.T
        self._err = np.zeros(6)
        self._H = np.zeros((6, 6))
        self._g = np.zeros(6)
        self._dq = np.zeros(6)
        self._damp = DLS_LAMBDA**2 * np.eye(6)
        self._Rerr = np.zeros((3, 3))
        self.p_ref, self.R_ref = self.tcp_pose()
        self.q_cmd = self.joint_positions()
        # Gravity compensation of the payload below the sensor (see tare()).
        self._tool_mass, self._tool_com = tool_inertial(cell)
        self._p_ft_tcp = self._ft_xmat.T @ (self._tcp_xpos - self._ft_xpos)
        self.payload_mass = self._tool_mass
        self.payload_com = self._tool_com.copy()
        self._payload_com_t = tuple(self.payload_com.tolist())
        self._g_tare = np.zeros(6)
        self._g_now = np.zeros(6)
        self._compensate = False

    def set_payload(self, peg_mass: float) -> None:
        """Compensate a held peg of ``peg_mass`` as if its centre of mass lay at the TCP (the
        pads) besides the tool's own load; takes effect at the next :meth:`tare`."""
        m = self._tool_mass + peg_mass
        self.payload_com = (self._tool_mass * self._tool_com + peg_mass * self._p_ft_tcp) / m
        self._payload_com_t = tuple(self.payload_com.tolist())
        self.payload_mass = m

    def _gravity_wrench(self) -> tuple[float, float, float, float, float, float]:
        """The payload's weight as an external wrench on the tool, sensor frame:
        ``f = R_world_ft^T (0, 0, -m g)``, ``tau = c x f`` (scalar arithmetic: numpy's
        cross product costs more than the whole sum on 3-vectors)."""
        w = -GRAVITY * self.payload_mass
        zx, zy, zz = self._z_world_in_ft.tolist()
        gx, gy, gz = w * zx, w * zy, w * zz
        cx, cy, cz = self._payload_com_t
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
        self._g_tare[:] = self._gravity_wrench()
        self._compensate = True

    def set_compliant(self, on: bool) -> None:
        """Let the F/T signal drive the admittance (True) or hold the reference stiffly."""
        if not on:
            self.absorb_offset()
        self.compliant = on

    # -- state from the robot's own sensors ----------------------------------------------

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(p_world_tcp, R_world_tcp)`` from the measured joint angles."""
        d, s = self.cell.data, self.cell.ids.tcp_site
        return d.site_xpos[s].copy(), d.site_xmat[s].reshape(3, 3).copy()

    def tcp_height(self) -> float:
        """Height of the TCP from the measured joint angles [m] (no copies)."""
        return float(self._tcp_xpos[2])

    def joint_positions(self) -> np.ndarray:
        return self._qpos.copy()

    def read_ft(self) -> np.ndarray:
        """Sample the F/T sensor; update and return the world-frame wrench at the TCP.

        The sensor's wrench, less the change of the payload's weight since the tare
        (``w - W_g(R) + W_g(R_tare)``), is turned into the world frame by ``R_world_ft`` (numpy's
        matrix product) and moved from the sensor's origin to the TCP:
        ``tau_tcp = tau_ft + (p_ft - p_tcp) x f`` (plain floats, rounded as numpy's element-wise
        operations round)."""
        w = self.ft.sample(self._raw)
        if self._compensate:
            self._g_now[:] = self._gravity_wrench()
            np.subtract(w, self._g_now, out=self.wrench_sensor)
            self.wrench_sensor += self._g_tare
        else:
            self.wrench_sensor[:] = w
        R_world_ft = self._ft_xmat
        wrench = self.wrench
        f0, f1, f2 = np.matmul(R_world_ft, self._sensor_f, out=self._wrench_f).tolist()
        m0, m1, m2 = np.matmul(R_world_ft, self._sensor_m, out=self._wrench_m).tolist()
        x0, x1, x2 = self._ft_xpos.tolist()
        y0, y1, y2 = self._tcp_xpos.tolist()
        r0, r1, r2 = x0 - y0, x1 - y1, x2 - y2
        self._wrench_m[:] = (m0 + (r1 * f2 - r2 * f1), m1 + (r2 * f0 - r0 * f2),
                             m2 + (r0 * f1 - r1 * f0))
        return wrench

    # -- commands ---------------------------------------------------------------------------

    def set_reference(self, p: np.ndarray, R: np.ndarray) -> None:
        self.p_ref = np.array(p, dtype=float)
        self.R_ref = np.array(R, dtype=float)

    def commanded_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(p_cmd, R_cmd)``: the reference displaced by the compliant offset,
        ``p_ref + e_p`` and ``exp([e_r]_x) R_ref``."""
        e = self.admittance.offset
        return self.p_ref + e[:3], self._commanded_rotation(*e[3:].tolist())

    def _commanded_rotation(self, rx: float, ry: float, rz: float) -> np.ndarray:
        """``exp([e_r]_x) R_ref`` for the rotation offset ``e_r = (rx, ry, rz)`` (``R_ref``
        itself while it is zero, as it is whenever the arm is not compliant)."""
        if rx == 0.0 and ry == 0.0 and rz == 0.0:
            return self.R_ref
        return exp_so3((rx, ry, rz)) @ self.R_ref

    def absorb_offset(self) -> None:
        """Move the compliant offset into the reference (the commanded pose is unchanged)."""
        self.p_ref, self.R_ref = self.commanded_pose()
        self.admittance.offset[:] = 0.0
        self.admittance.velocity[:] = 0.0

    def update(self, dt: float) -> None:
        """One control tick: F/T -> admittance -> IK -> joint targets."""
        self.read_ft()
        if self.compliant:
            self.admittance.step(self.wrench, dt)
        e0, e1, e2, rx, ry, rz = self.admittance.offset.tolist()
        px, py, pz = self.p_ref.tolist()
        px, py, pz = px + e0, py + e1, pz + e2  # p_cmd, as numpy's sum rounds
        R_cmd = self._commanded_rotation(rx, ry, rz)
        m, sd, site = self._model, self._scratch, self._tcp_site
        J, JT, err, H, g, dq = self._J, self._JT, self._err, self._H, self._g, self._dq
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
                # Damped least squares: dq = (J^T J + lambda^2 I)^-1 J^T err, Cholesky-factored
                # (the matrix is symmetric positive definite).
                np.matmul(JT, J, out=H)
                H += self._damp
                mujoco.mju_cholFactor(H, 0.0)
            x, y, z = self._s_tcp_xpos.tolist()
            np.matmul(R_cmd, self._s_R_tcp_world, out=self._Rerr)
            e = (px - x, py - y, pz - z, *log_so3_tuple(self._Rerr))
            err[:] = e
            np.matmul(JT, err, out=g)
            mujoco.mju_cholSolve(dq, H, g)
            steps = dq.tolist()
            if max(steps) > step_max or min(steps) < -step_max:  # clip only where it acts
                np.minimum(dq, step_max, out=dq)
                np.maximum(dq, -step_max, out=dq)
            q += dq
            if max(e) < 1e-7 and min(e) > -1e-7:
                break
        self._ctrl[:] = q


def tool_inertial(cell: Cell) -> tuple[float, np.ndarray]:
    """Mass and centre of mass (sensor frame) of everything below the F/T sensor's site: the
    robot's own tool (sensor body, RG2), its design data (the gripper's fingers move
    symmetrically, so the centre does not depend on the opening)."""
    m, ids = cell.model, cell.ids
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    body = int(m.site_bodyid[ids.ft_site])
    mass = float(m.body_subtreemass[body])
    com_world = d.subtree_com[body]
    R = d.site_xmat[ids.ft_site].reshape(3, 3)
    return mass, R.T @ (com_world - d.site_xpos[ids.ft_site])


def _block(array: np.ndarray, index: np.ndarray) -> np.ndarray:
    """The view ``array[i0:i0 + n]`` for ``index = i0 .. i0 + n - 1`` (the cell builds the arm's
    joints and actuators as contiguous runs)."""
    i0 = int(index[0])
    if not np.array_equal(index, np.arange(i0, i0 + len(index))):
        raise ValueError("the arm's joints and actuators must be numbered contiguously")
    return array[i0:i0 + len(index)]
