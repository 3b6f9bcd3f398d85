"""Named element indices of the assembly cell (:class:`CellIds`), looked up once per model.

Kept apart from :mod:`vgs.sim.cell` so that the pieces the cell is built from (the pads' stick
state, :mod:`vgs.sim.stiction`) can take the ids without importing the cell.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from vgs.sim import ur5


@dataclass(frozen=True)
class CellIds:
    """Indices of the named elements the rest of vgs uses."""

    arm_qpos: np.ndarray
    arm_dof: np.ndarray
    arm_act: np.ndarray
    finger_act: np.ndarray
    finger_qpos: np.ndarray
    peg_body: int
    peg_qpos: int
    peg_dof: int
    hole_mocap: int
    tcp_site: int
    flange_site: int
    ft_site: int
    ft_force_adr: int
    ft_torque_adr: int
    peg_geom: int
    hole_geoms: np.ndarray
    pad_geoms: np.ndarray
    table_geom: int


def cell_ids(m: mujoco.MjModel) -> CellIds:
    """The :class:`CellIds` of a model built by :func:`vgs.sim.cell.build_spec`."""

    def jid(name: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)

    def aid(name: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)

    def sid(name: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)

    def gid(name: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)

    arm_j = [jid(n) for n in ur5.JOINT_NAMES]
    peg_j = jid("peg_free")
    hole_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "hole")
    hole_geoms = np.flatnonzero(m.geom_bodyid == hole_body)
    fsens = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, "ft_force")
    tsens = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, "ft_torque")
    return CellIds(
        arm_qpos=np.array([m.jnt_qposadr[j] for j in arm_j]),
        arm_dof=np.array([m.jnt_dofadr[j] for j in arm_j]),
        arm_act=np.array([aid(n) for n in ur5.JOINT_NAMES]),
        finger_act=np.array([aid("finger_left"), aid("finger_right")]),
        finger_qpos=np.array([m.jnt_qposadr[jid("finger_left_joint")],
                              m.jnt_qposadr[jid("finger_right_joint")]]),
        peg_body=mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "peg"),
        peg_qpos=int(m.jnt_qposadr[peg_j]),
        peg_dof=int(m.jnt_dofadr[peg_j]),
        hole_mocap=int(m.body_mocapid[hole_body]),
        tcp_site=sid("tcp"),
        flange_site=sid("flange"),
        ft_site=sid("ft"),
        ft_force_adr=int(m.sensor_adr[fsens]),
        ft_torque_adr=int(m.sensor_adr[tsens]),
        peg_geom=gid("peg"),
        hole_geoms=hole_geoms,
        pad_geoms=np.array([gid("pad_left"), gid("pad_right")]),
        table_geom=gid("table"),
    )
