"""The RG2 friction grasp holds below its capacity and slips above it.

The robot grasps the peg lying on the table with the real grasp primitive and lifts it. Two
physics checks on the pads' contacts (:mod:`vgs.sim.rg2`, docs/cell.md "The grasp"):

- held horizontal 35 mm from its centre of mass for 10 s (a moment m g c = 0.19 N m about the
  pinch axis, under half the capacity), the peg turns less than 0.5 deg in the pads;
- a moment about the pinch axis applied to the peg and ramped slowly from zero turns it in the
  pads (more than 1 deg) within 15 % of the capacity that
  :func:`vgs.sim.rg2.grasp_moment_capacity` states (0.44 N m with the defaults);
- with the peg's rim pressed on the table (a second contact on the peg), a third of the
  capacity held for 5 s turns it less than 0.2 deg (the pads' stick state,
  :mod:`vgs.sim.stiction`), and the pads let go when the gripper opens.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from test_cell_ft_torque import grasp_and_lift
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.grasp import grasp
from vgs.assembly.strategy import AssemblyModule
from vgs.config import override, profile
from vgs.control.robot import Robot
from vgs.sim.cell import Cell
from vgs.sim.rg2 import grasp_moment_capacity
from vgs.sim.stiction import WELD_NAME

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


def rim_on_table(seed: int = 5) -> tuple[Cell, Robot]:
    """Grasp the centre of one scene's peg, turn it upright and make the approach's plane
    contact: the lower rim pressed on the table, the peg's second contact."""
    cfg = profile("paper")
    runner = EpisodeRunner(cfg)
    cell, cam = runner.cell(cfg.cell.peg)
    cell.reset(np.random.default_rng(seed))
    hm = cam.capture(cell.data)
    robot = Robot(cell, cfg.controller, np.random.default_rng([seed, 1]))
    command = offset_policy(0.0)(hm)
    row, col = hm.world_to_pixel(command.x, command.y)
    robot.run(0.2)
    robot.arm.tare()
    assert grasp(robot, command.x, command.y, command.yaw, float(hm.depth[row, col])).success
    hole = cfg.cell.hole
    module = AssemblyModule(robot, cfg.assembly, cfg.cell.peg, hole.nominal_xy, hole.depth,
                            hole.clearance)
    module._begin("transport")
    module.transport()
    module._begin("approach")
    module.approach()
    robot.run(0.5)
    return cell, robot


@pytest.mark.slow
def test_grasp_holds_with_the_rim_on_the_table() -> None:
    """A third of the capacity about the pinch axis, held 5 s with the peg's rim pressed on the
    table: MuJoCo's regularised friction alone let it creep 0.83 deg; the pads' stick state
    (:mod:`vgs.sim.stiction`) holds it."""
    cell, robot = rim_on_table()
    assert cell.stiction is not None and cell.stiction.stuck
    d, peg = cell.data, cell.ids.peg_body
    moment = grasp_moment_capacity(cell.cfg.gripper) / 3.0
    start, breaks = turn_in_pads(cell), cell.stiction.breaks
    for _ in range(int(round(5.0 / robot.dt))):
        d.xfrc_applied[peg, 3:] = moment * d.site_xmat[cell.ids.tcp_site].reshape(3, 3)[:, 1]
        robot.tick()
    # The weld carries part of the moment about the pinch axis (what the grasp watch records).
    assert abs(cell.stiction.weld_wrench()[1][1]) > 0.0
    d.xfrc_applied[peg] = 0.0
    assert abs(turn_in_pads(cell) - start) < 0.2
    assert cell.stiction.breaks == breaks


@pytest.mark.slow
def test_pads_let_go_when_the_gripper_opens() -> None:
    cell, robot = held_peg(0.0)
    assert cell.stiction is not None and cell.stiction.stuck
    robot.gripper.command(cell.cfg.gripper.stroke)
    robot.run(0.5)
    assert not cell.stiction.stuck
    assert not np.any(cell.stiction.weld_wrench()[1])  # a released weld carries nothing
    # Nothing holds the peg: it has fallen from the lift height onto the table.
    assert cell.peg_pose()[0][2] < 2 * cell.cfg.peg.radius


def test_stiction_can_be_switched_off() -> None:
    """``cell.gripper.stiction=False`` builds the cell without the weld (MuJoCo's friction
    alone, the cell before 2026-12-02)."""
    cfg = override(profile("smoke"), "cell.gripper.stiction", False)
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    assert cell.stiction is None
    assert mujoco.mj_name2id(cell.model, mujoco.mjtObj.mjOBJ_EQUALITY, WELD_NAME) == -1
