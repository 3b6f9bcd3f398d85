"""The wrist F/T sensor sees the held peg's weight and gravitational moment m g l.

The robot grasps a peg lying on the table at offsets l along its axis (0, +-20, +-35 mm) with
the real grasp primitive, after taring the sensor at the lifted pose with the gripper empty.
After settling, the torque about the pinch axis (tool y, the axis the peg's weight turns the
peg about) must equal m g l within 3 %, where l is the horizontal distance of the peg's centre
of mass from the sensor's axis along the pads (ground truth). Sensor noise is switched off:
the test is about the physics of the reading, not the noise model.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from vgs.assembly.grasp import LIFT_HEIGHT, grasp, tool_rotation
from vgs.config import override, profile
from vgs.control.robot import Robot
from vgs.sim.cell import Cell

GRAVITY = 9.81
PEG_XY = np.array([0.42, -0.12])
PEG_YAW = 0.3


@pytest.fixture(scope="module")
def cell() -> Cell:
    cfg = override(profile("paper"), "cell.ft.force_noise", 0.0)
    cfg = override(cfg, "cell.ft.torque_noise", 0.0)
    return Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)


def grasp_and_lift(cell: Cell, offset: float) -> tuple[Robot, float]:
    """Reset, lay the peg at a fixed pose, tare above it with the gripper empty, grasp at
    ``offset`` along the peg axis with the real grasp primitive and lift; return the robot and
    the realised offset (ground truth)."""
    cfg = profile("paper")
    cell.reset(np.random.default_rng(0))
    cell.set_peg_lying(*PEG_XY, PEG_YAW)
    mujoco.mj_forward(cell.model, cell.data)
    robot = Robot(cell, cfg.controller, np.random.default_rng(1))
    axis = np.array([math.cos(PEG_YAW), math.sin(PEG_YAW)])
    x, y = PEG_XY + offset * axis
    robot.move_to(np.array([x, y, LIFT_HEIGHT]), tool_rotation(PEG_YAW), speed=0.3, settle=0.5)
    robot.ft.tare()  # gripper empty, at the pose the peg will be lifted to
    result = grasp(robot, x, y, PEG_YAW, 2 * cell.cfg.peg.radius)
    assert result.success
    return robot, result.offset


def hold_and_measure(cell: Cell, offset: float) -> dict[str, float]:
    """Grasp at ``offset`` along the peg axis, lift, settle; average the reading over 0.5 s."""
    robot, realised = grasp_and_lift(cell, offset)
    robot.run(1.0)
    torque, force, lever, tilt = [], [], [], []
    d, ids = cell.data, cell.ids
    for _ in range(50):
        robot.tick()
        torque.append(robot.arm.wrench_sensor[4])  # about tool y, the pinch axis
        force.append(robot.arm.wrench_sensor[2])  # along tool z (down)
        p_peg, R_peg = cell.peg_pose()
        x_ft = d.site_xmat[ids.ft_site].reshape(3, 3)[:, 0]
        pads = np.array([x_ft[0], x_ft[1], 0.0]) / math.hypot(x_ft[0], x_ft[1])
        lever.append(float(np.dot(p_peg - d.site_xpos[ids.ft_site], pads)))
        tilt.append(math.degrees(math.asin(min(1.0, abs(R_peg[2, 2])))))
    return {"torque": float(np.mean(torque)), "force": float(np.mean(force)),
            "lever": float(np.mean(lever)), "tilt": max(tilt), "realised": realised}


@pytest.mark.slow
@pytest.mark.parametrize("offset_mm", [0.0, 20.0, -20.0, 35.0, -35.0])
def test_torque_matches_m_g_l(cell: Cell, offset_mm: float) -> None:
    m = cell.cfg.peg.mass
    r = hold_and_measure(cell, offset_mm / 1000.0)
    assert r["tilt"] < 5.0, "the peg is no longer horizontal in the grasp"
    assert abs(abs(r["realised"]) - abs(offset_mm) / 1000.0) < 0.002
    assert abs(abs(r["lever"]) - abs(r["realised"])) < 0.002
    assert r["force"] == pytest.approx(m * GRAVITY, rel=0.03)
    expected = m * GRAVITY * abs(r["lever"])
    if offset_mm == 0.0:
        assert abs(r["torque"]) < 0.03 * m * GRAVITY * 0.035  # 3 % of the moment at 35 mm
    else:
        assert abs(r["torque"]) == pytest.approx(expected, rel=0.03)
