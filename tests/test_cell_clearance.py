"""Peg against hole: a nominal peg goes in, one 0.5 mm larger than the hole does not.

The free peg is placed upright and centred over the hole with its lower face 0.2 mm above the
entrance and pushed down with a force ramped to 20 N (``data.xfrc_applied``); a PD torque holds
it upright. The 32-wedge hole approximates the circle within ``HoleConfig.surface_tolerance``.
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from vgs.config import HoleConfig, PegConfig, profile
from vgs.control.transforms import log_so3
from vgs.sim.cell import Cell

PUSH = 20.0  # N
RAMP = 0.5  # s
DURATION = 2.0  # s


def push_into_hole(peg: PegConfig, hole: HoleConfig) -> float:
    """Height of the peg's lower face above the table after the push [m]."""
    cfg = profile("paper")
    cell = Cell(replace(cfg.cell, peg=peg, hole=hole), cfg.controller.joint_kp,
                cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(3))
    m, d, ids = cell.model, cell.data, cell.ids
    q = ids.peg_qpos
    d.qpos[q:q + 3] = [*cell.hole_xy, hole.depth + 0.5 * peg.length + 0.0002]
    d.qpos[q + 3:q + 7] = [1.0, 0.0, 0.0, 0.0]
    d.qvel[ids.peg_dof:ids.peg_dof + 6] = 0.0
    mujoco.mj_forward(m, d)
    b = ids.peg_body
    dt = m.opt.timestep
    for i in range(int(DURATION / dt)):
        R = d.xmat[b].reshape(3, 3)
        omega = R @ d.qvel[ids.peg_dof + 3:ids.peg_dof + 6]  # free joint: body-frame rates
        d.xfrc_applied[b, :3] = [0.0, 0.0, -PUSH * min(1.0, i * dt / RAMP)]
        d.xfrc_applied[b, 3:] = -5.0 * log_so3(R) - 0.2 * omega
        cell.step(1)
    p, _ = cell.peg_pose()
    return float(p[2] - 0.5 * peg.length)


def test_surface_tolerance_within_a_tenth_of_a_millimetre() -> None:
    assert HoleConfig().surface_tolerance < 1e-4


@pytest.mark.slow
def test_nominal_peg_goes_to_the_bottom() -> None:
    bottom = push_into_hole(PegConfig(), HoleConfig())
    assert bottom < 0.0005  # on the table inside the through hole


@pytest.mark.slow
def test_peg_larger_than_the_hole_stays_out() -> None:
    hole = HoleConfig(peg_diameter=0.030, clearance=0.001)
    peg = PegConfig(diameter=0.0315)
    assert hole.diameter < peg.diameter
    bottom = push_into_hole(peg, hole)
    assert bottom > hole.depth - 0.0001
