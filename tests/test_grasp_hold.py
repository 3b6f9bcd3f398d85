"""The RG2 friction grasp holds below its capacity and slips above it.

The robot grasps the peg lying on the table with the real grasp primitive and lifts it. Two
physics checks on the pads' contacts (:mod:`vgs.sim.rg2`, docs/cell.md "The grasp"):

- held horizontal 35 mm from its centre of mass for 10 s (a moment m g c = 0.19 N m about the
  pinch axis, under half the capacity), the peg turns less than 0.5 deg in the pads;
- a moment about the pinch axis applied to the peg and ramped slowly from zero turns it in the
  pads (more than 1 deg) within 15 % of the capacity that
  :func:`vgs.sim.rg2.grasp_moment_capacity` states (0.44 N m with the defaults).
"""

from __future__ import annotations

import math

import pytest

from test_cell_ft_torque import grasp_and_lift
from vgs.config import profile
from vgs.control.robot import Robot
from vgs.sim.cell import Cell
from vgs.sim.rg2 import grasp_moment_capacity

RAMP_RATE = 0.05  # N m per second: slow against the grasp's dynamics


def held_peg(offset: float) -> tuple[Cell, Robot]:
    """Grasp the peg ``offset`` metres from its centre along its axis and lift it."""
    cfg = profile("paper")
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    robot, _ = grasp_and_lift(cell, offset)
    robot.run(0.5)
    return cell, robot


def turn_in_pads(cell: Cell) -> float:
    """Angle of the peg's axis out of the pads' long side (tool x), about the pinch axis [deg]."""
    d, ids = cell.data, cell.ids
    R_tcp = d.site_xmat[ids.tcp_site].reshape(3, 3)
    axis = R_tcp.T @ d.xmat[ids.peg_body].reshape(3, 3)[:, 2]
    return math.degrees(math.atan2(axis[2], abs(axis[0])))


@pytest.mark.slow
def test_grasp_holds_below_capacity() -> None:
    cell, robot = held_peg(0.035)
    start = turn_in_pads(cell)
    robot.run(10.0)
    assert abs(turn_in_pads(cell) - start) < 0.5


@pytest.mark.slow
def test_grasp_slips_at_its_capacity() -> None:
    cell, robot = held_peg(0.0)
    capacity = grasp_moment_capacity(cell.cfg.gripper)
    d, peg = cell.data, cell.ids.peg_body
    start = turn_in_pads(cell)
    t, slipped_at = 0.0, None
    while t < 2.0 * capacity / RAMP_RATE:
        pinch = d.site_xmat[cell.ids.tcp_site].reshape(3, 3)[:, 1]
        d.xfrc_applied[peg, 3:] = RAMP_RATE * t * pinch
        robot.tick()
        t += robot.dt
        if abs(turn_in_pads(cell) - start) > 1.0:
            slipped_at = RAMP_RATE * t
            break
    d.xfrc_applied[peg] = 0.0
    assert slipped_at is not None, "the grasp never slipped"
    assert slipped_at == pytest.approx(capacity, rel=0.15)


def test_capacity_formula() -> None:
    """mu F L / 4 per pad, two pads, plus the patches' small torsional share."""
    gripper = profile("paper").cell.gripper
    line = 2 * gripper.pad_friction * gripper.force * 0.022 / 4
    assert grasp_moment_capacity(gripper) == pytest.approx(line, rel=0.03)
    assert grasp_moment_capacity(gripper) > line
