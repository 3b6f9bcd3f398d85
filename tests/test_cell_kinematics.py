"""The ``flange`` site of the built cell against UR's published DH forward kinematics."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from vgs.config import profile
from vgs.sim import ur5
from vgs.sim.cell import Cell


@pytest.fixture(scope="module")
def cell() -> Cell:
    cfg = profile("paper")
    return Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)


def test_flange_matches_dh_forward_kinematics(cell: Cell) -> None:
    rng = np.random.default_rng(7)
    m, d, ids = cell.model, cell.data, cell.ids
    lo, hi = ur5.JOINT_RANGE[:, 0], ur5.JOINT_RANGE[:, 1]
    for _ in range(50):
        q = rng.uniform(lo, hi)
        d.qpos[ids.arm_qpos] = q
        mujoco.mj_kinematics(m, d)
        T = ur5.forward_kinematics(q)
        p = d.site_xpos[ids.flange_site]
        R = d.site_xmat[ids.flange_site].reshape(3, 3)
        assert np.linalg.norm(p - T[:3, 3]) < 1e-4, q
        assert np.abs(R - T[:3, :3]).max() < 1e-6, q


def test_joint_names_and_order(cell: Cell) -> None:
    m = cell.model
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(6)]
    assert tuple(names) == ur5.JOINT_NAMES


def test_dh_zero_pose() -> None:
    T = ur5.forward_kinematics(np.zeros(6))
    # UR5 at zero: the arm stretched along -x, flange at x = -(a2 + a3), y = -(d4 + d6).
    assert T[:3, 3] == pytest.approx([-0.81725, -0.19145, -0.005491], abs=1e-6)
