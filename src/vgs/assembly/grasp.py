"""Grasp primitive: top-down approach, force-limited closing, lift; success from finger width.

``grasp(x, y, yaw)``: the TCP comes down to (x, y) with the tool z axis pointing down and the
pads' long side (tool x) along the world heading ``yaw``; the fingers close along tool y. Height
of the grasp: ``z = h(x, y) - r_nominal`` from the heightmap (the peg's axis height), kept at
least ``MIN_TCP_HEIGHT`` above the table so the pads clear it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vgs import vecmath as vm
from vgs.control.robot import Robot
from vgs.control.transforms import matmul, rot_z

MIN_TCP_HEIGHT = 0.013  # pad half-height 11 mm + 2 mm clearance
PREGRASP_HEIGHT = 0.12
LIFT_HEIGHT = 0.15
MIN_GRASP_WIDTH = 0.004  # narrower than this: the fingers closed on nothing
R_DOWN = np.diag([1.0, -1.0, -1.0])  # tool z down, tool x along world x


@dataclass(frozen=True)
class GraspResult:
    """Outcome of one grasp.

    Attributes:
        success: The fingers hold something after the lift (width reading).
        width: Finger width after the lift [m].
        offset: Ground truth for analysis only: signed distance along the peg axis from the peg's
            centre of mass to the grasp point (pad midpoint) [m]; NaN if the peg is not held.
    """

    success: bool
    width: float
    offset: float


def tool_rotation(yaw: float) -> np.ndarray:
    """``R_world_tcp`` of a top-down grasp with the pads' long side at heading ``yaw``."""
    return matmul(rot_z(yaw), R_DOWN)


def grasp(robot: Robot, x: float, y: float, yaw: float, surface_height: float) -> GraspResult:
    """Execute the grasp primitive.

    Args:
        robot: The robot.
        x: Grasp point, world frame [m].
        y: Grasp point, world frame [m].
        yaw: Heading of the pads' long side [rad].
        surface_height: Heightmap value at (x, y) [m].
    """
    robot.phase = "grasp"
    cfg = robot.cell.cfg
    R = tool_rotation(yaw)
    z = max(surface_height - cfg.peg.radius, MIN_TCP_HEIGHT)
    robot.arm.set_compliant(False)
    robot.gripper.command(cfg.gripper.stroke)
    robot.move_to(np.array([x, y, PREGRASP_HEIGHT]), R, speed=0.4, angular_speed=2.0, settle=0.0)
    robot.move_to(np.array([x, y, z]), R, speed=0.15, settle=0.1)
    robot.gripper.command(0.0)
    last = robot.gripper.width()
    for _ in range(int(1.5 / robot.dt / 10)):
        robot.run(10 * robot.dt)
        w = robot.gripper.width()
        if abs(w - last) < 1e-5 and robot.gripper.width() < cfg.gripper.stroke - 0.001:
            break
        last = w
    robot.run(0.2)
    robot.move_to(np.array([x, y, LIFT_HEIGHT]), R, speed=0.15, settle=0.2)
    width = robot.gripper.width()
    success = width > MIN_GRASP_WIDTH
    return GraspResult(success=success, width=width, offset=realised_offset(robot) if success
                       else float("nan"))


def realised_offset(robot: Robot) -> float:
    """Ground truth (analysis only): pad midpoint minus peg centre, along the peg axis [m]."""
    p_peg, R_peg = robot.cell.peg_pose()
    tcp = robot.cell.data.site_xpos[robot.cell.ids.tcp_site]
    return vm.dot((tcp - p_peg).tolist(), R_peg[:, 2].tolist())
