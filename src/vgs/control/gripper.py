"""RG2 command interface: opening targets ramped at the RG2's finger speed, force-limited servos.

The width reading is the finger joints' opening (the RG2 reports its finger width the same way).
"""

from __future__ import annotations

from vgs.config import GripperConfig
from vgs.sim.cell import Cell


class Gripper:
    """Open/close the RG2.

    Args:
        cell: The simulated cell.
        cfg: Gripper configuration.
    """

    def __init__(self, cell: Cell, cfg: GripperConfig) -> None:
        self.cell = cell
        self.cfg = cfg
        self.target = cfg.stroke / 2  # per-finger opening target [m]
        self._acts = [int(a) for a in cell.ids.finger_act]
        left, right = (int(q) for q in cell.ids.finger_qpos)
        if right != left + 1:
            raise ValueError("the two finger joints must be numbered contiguously")
        self._finger_qpos = cell.data.qpos[left:right + 1]  # a view

    def command(self, width: float) -> None:
        """Set the target opening between the pads [m] (0 = closed, stroke = open)."""
        self.target = min(max(width / 2, 0.0), self.cfg.stroke / 2)

    def update(self, dt: float) -> None:
        """Ramp each finger's servo target toward the opening target at the closing speed."""
        ctrl = self.cell.data.ctrl
        step = self.cfg.closing_speed / 2 * dt
        target = self.target
        for a in self._acts:
            c = float(ctrl[a])
            if c != target:
                ctrl[a] = c + min(max(target - c, -step), step)

    def width(self) -> float:
        """Finger width reading [m]: the two fingers' joint openings summed (as
        :meth:`vgs.sim.cell.Cell.finger_opening`, without its per-call indexing)."""
        left, right = self._finger_qpos.tolist()
        return left + right
