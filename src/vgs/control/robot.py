"""The robot as the assembly module sees it: arm, gripper and F/T sensor on one clock.

:class:`Robot` owns the control loop. Each :meth:`Robot.tick` advances one control period
(``sim.control_decimation`` physics steps). Motion primitives move the admittance *reference*
along straight lines at bounded speed; the compliant offset rides on top of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from vgs import vecmath as vm
from vgs.config import ControllerConfig
from vgs.control.arm import ArmController
from vgs.control.gripper import Gripper
from vgs.sim.cell import Cell
from vgs.sim.ft_sensor import FTSensor


@dataclass
class Trace:
    """Per-tick signals for figures and videos (kept only when asked for: it costs time).

    ``qpos`` holds a copy of the whole ``data.qpos`` per tick, so that an episode can be
    rendered afterwards from the recorded states (:mod:`vgs.render`) without rendering in the
    control loop.
    """

    time: list[float] = field(default_factory=list)
    wrench: list[np.ndarray] = field(default_factory=list)
    tcp: list[np.ndarray] = field(default_factory=list)
    peg_tip: list[np.ndarray] = field(default_factory=list)
    phase: list[str] = field(default_factory=list)
    qpos: list[np.ndarray] = field(default_factory=list)


class Robot:
    """UR5 + RG2 + wrist F/T on the simulated cell.

    Args:
        cell: The cell (already reset).
        cfg: Controller configuration.
        rng: Random generator (sensor noise).
        trace: Record per-tick signals.
    """

    def __init__(self, cell: Cell, cfg: ControllerConfig, rng: np.random.Generator,
                 trace: bool = False) -> None:
        self.cell = cell
        self.cfg = cfg
        self.dt = cell.cfg.sim.control_dt
        self.decimation = cell.cfg.sim.control_decimation
        self.ft = FTSensor(cell.cfg.ft, self.dt, rng)
        self.arm = ArmController(cell, cfg, self.ft)
        self.gripper = Gripper(cell, cell.cfg.gripper)
        self.trace = Trace() if trace else None
        self.phase = "idle"
        self._tip_site = None
        # Called after every control tick: records and tests read the simulator here (ground
        # truth for analysis); nothing in the controller does.
        self.observers: list[Callable[[], None]] = []

    @property
    def time(self) -> float:
        return float(self.cell.data.time)

    def tick(self) -> None:
        """One control period."""
        self.gripper.update(self.dt)
        self.arm.update(self.dt)
        self.cell.step(self.decimation)
        if self.trace is not None:
            self._record()
        for observer in self.observers:
            observer()

    def _record(self) -> None:
        t = self.trace
        d, ids = self.cell.data, self.cell.ids
        t.time.append(self.time)
        t.wrench.append(self.arm.wrench.copy())
        t.tcp.append(d.site_xpos[ids.tcp_site].copy())
        # Ground truth for the figure only: the lower end of the peg.
        p, R = self.cell.peg_pose()
        half = 0.5 * self.cell.cfg.peg.length * R[:, 2]
        t.peg_tip.append(p - half if (p - half)[2] < (p + half)[2] else p + half)
        t.phase.append(self.phase)
        t.qpos.append(d.qpos.copy())

    def run(self, duration: float, until: Callable[[], bool] | None = None) -> bool:
        """Tick for ``duration`` seconds or until ``until()`` is true; return whether it was."""
        n = max(1, int(round(duration / self.dt)))
        for _ in range(n):
            self.tick()
            if until is not None and until():
                return True
        return False

    def move_to(self, p: np.ndarray | vm.Vec3, R: np.ndarray | vm.Mat3, speed: float,
                angular_speed: float = 1.0, until: Callable[[], bool] | None = None,
                settle: float = 0.2) -> bool:
        """Move the reference on a straight line (and a geodesic in rotation) to ``(p, R)``:
        ``p(s) = p0 + s (p - p0)``, ``R(s) = exp(s [w]_x) R0`` with ``w = log(R R0^T)`` and the
        smoothstep ``s = 3 u^2 - 2 u^3`` of the time fraction ``u`` (plain floats).

        Returns True when ``until()`` fired, False when the motion finished without it.
        """
        p0, R0 = self.arm.reference_t
        p1 = p if isinstance(p, tuple) else vm.vec3(p)
        R1 = R if isinstance(R, tuple) else vm.mat3(R)
        dx, dy, dz = vm.sub(p1, p0)
        w0, w1, w2 = vm.log_so3(vm.mmt(R1, R0))
        duration = max(vm.norm((dx, dy, dz)) / speed, vm.norm((w0, w1, w2)) / angular_speed,
                       self.dt)
        n = int(math.ceil(duration / self.dt))
        x0, y0, z0 = p0
        set_reference, exp_so3, mm = self.arm.set_reference, vm.exp_so3, vm.mm
        for k in range(1, n + 1):
            s = k / n
            s = s * s * (3 - 2 * s)  # smoothstep: zero speed at both ends
            set_reference((x0 + s * dx, y0 + s * dy, z0 + s * dz),
                          mm(exp_so3((s * w0, s * w1, s * w2)), R0))
            self.tick()
            if until is not None and until():
                return True
        return self.run(settle, until) if settle > 0 else False
