"""The arm controller: reference trajectory + admittance offset -> joint servo targets.

Each control tick (period ``sim.timestep * sim.control_decimation``):

1. read the F/T sensor and express the tared wrench at the TCP in the world frame:
   ``f_w = R_world_ft f_ft``, ``tau_w = R_world_ft tau_ft + (p_ft - p_tcp) x f_w``;
2. advance the admittance offset ``e`` (see :mod:`vgs.control.admittance`);
3. commanded pose ``p_cmd = p_ref + e_p``, ``R_cmd = exp([e_r]_x) R_ref``;
4. differential IK on the *commanded* joint vector (the robot's kinematic model evaluated on a
   scratch ``MjData``, independent of servo lag) with damped least squares:
   ``q_cmd <- q_cmd + (J^T J + lambda^2 I)^-1 J^T [p_cmd - p(q_cmd); log(R_cmd R(q_cmd)^T)]``
   (two Newton steps per tick),
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
from vgs.control.transforms import exp_so3, log_so3
from vgs.sim.cell import Cell
from vgs.sim.ft_sensor import FTSensor

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
        self._jacp = np.zeros((3, cell.model.nv))
        self._jacr = np.zeros((3, cell.model.nv))
        self.wrench = np.zeros(6)  # tared external wrench at the TCP, world frame
        self.wrench_sensor = np.zeros(6)  # tared external wrench, sensor frame
        self.p_ref, self.R_ref = self.tcp_pose()
        self._scratch = mujoco.MjData(cell.model)
        self.q_cmd = self.joint_positions()
        self._J = np.zeros((6, 6))
        self._err = np.zeros(6)
        self._damp = DLS_LAMBDA**2 * np.eye(6)
        self.compliant = False  # False: the F/T signal does not drive the admittance

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

    def joint_positions(self) -> np.ndarray:
        return self.cell.data.qpos[self.cell.ids.arm_qpos].copy()

    def read_ft(self) -> np.ndarray:
        """Sample the F/T sensor; update and return the world-frame wrench at the TCP."""
        d, ids = self.cell.data, self.cell.ids
        raw = np.concatenate(
            [d.sensordata[ids.ft_force_adr:ids.ft_force_adr + 3],
             d.sensordata[ids.ft_torque_adr:ids.ft_torque_adr + 3]]
        )
        w = self.ft.sample(raw)
        self.wrench_sensor = w
        R_world_ft = d.site_xmat[ids.ft_site].reshape(3, 3)
        f = R_world_ft @ w[:3]
        r = d.site_xpos[ids.ft_site] - d.site_xpos[ids.tcp_site]
        wrench = self.wrench
        wrench[:3] = f
        wrench[3:] = R_world_ft @ w[3:]
        wrench[3] += r[1] * f[2] - r[2] * f[1]
        wrench[4] += r[2] * f[0] - r[0] * f[2]
        wrench[5] += r[0] * f[1] - r[1] * f[0]
        return wrench

    # -- commands ---------------------------------------------------------------------------

    def set_reference(self, p: np.ndarray, R: np.ndarray) -> None:
        self.p_ref = np.asarray(p, dtype=float).copy()
        self.R_ref = np.asarray(R, dtype=float).copy()

    def commanded_pose(self) -> tuple[np.ndarray, np.ndarray]:
        e = self.admittance.offset
        if not e[3:].any():
            return self.p_ref + e[:3], self.R_ref
        return self.p_ref + e[:3], exp_so3(e[3:]) @ self.R_ref

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
        p_cmd, R_cmd = self.commanded_pose()
        m, ids, sd = self.cell.model, self.cell.ids, self._scratch
        J, err = self._J, self._err
        step_max = MAX_JOINT_SPEED * dt
        for _ in range(IK_ITERATIONS):
            sd.qpos[ids.arm_qpos] = self.q_cmd
            mujoco.mj_kinematics(m, sd)
            mujoco.mj_comPos(m, sd)
            mujoco.mj_jacSite(m, sd, self._jacp, self._jacr, ids.tcp_site)
            J[:3] = self._jacp[:, ids.arm_dof]
            J[3:] = self._jacr[:, ids.arm_dof]
            err[:3] = p_cmd - sd.site_xpos[ids.tcp_site]
            err[3:] = log_so3(R_cmd @ sd.site_xmat[ids.tcp_site].reshape(3, 3).T)
            # Damped least squares: dq = (J^T J + lambda^2 I)^-1 J^T err.
            dq = np.linalg.solve(J.T @ J + self._damp, J.T @ err)
            np.clip(dq, -step_max, step_max, out=dq)
            self.q_cmd += dq
            if np.abs(err).max() < 1e-7:
                break
        self.cell.data.ctrl[ids.arm_act] = self.q_cmd
