"""Cartesian admittance law.

The commanded TCP pose is the reference pose plus a compliant offset ``e`` (3 translations in the
world frame, 3 rotations as a rotation vector about world axes at the TCP) that obeys, per axis,

    M e'' + D e' + K e = w_ext + w_des,

with ``w_ext`` the tared external wrench at the TCP and ``w_des`` a desired wrench (the force the
tool should apply is ``-w_des``: ``w_des = (0, 0, -10, 0, 0, 0)`` presses down with 10 N). On an
axis with ``K > 0`` this is a spring-damper around the reference; with ``K = 0`` it is force
control: the offset moves at ``(w_ext + w_des) / D`` until the contact balances ``w_des``.

Damping: ``D = 2 zeta sqrt(K M)`` (critical for zeta = 1) on stiff axes. Force-controlled axes need
``D > k_servo dt`` for the discrete force loop through the stiff joint servos (Cartesian stiffness
~1e4 N/m, dt = 10 ms: D > 100 N s/m); they use ``ControllerConfig.force_damping`` (default
1500 N s/m), which also filters the stick-slip of the rubbing spiral.
"""

from __future__ import annotations

import numpy as np

from vgs import native
from vgs.config import ControllerConfig

K_FORCE_REF = np.array([2.0e4, 2.0e4, 2.0e4, 40.0, 40.0, 40.0])


class Admittance:
    """Integrates the compliant offset of the commanded pose.

    Args:
        cfg: Controller configuration (stiffness, virtual mass, damping ratio, speed limits).
    """

    def __init__(self, cfg: ControllerConfig) -> None:
        self.cfg = cfg
        self.mass = np.array([cfg.trans_mass] * 3 + [cfg.rot_inertia] * 3)
        self.offset = np.zeros(6)
        self.velocity = np.zeros(6)
        self.wrench_des = np.zeros(6)
        self.vmax = np.array([cfg.max_speed] * 3 + [cfg.max_angular_speed] * 3)
        # Filled in place (set_stiffness), never replaced: the arm's C tick holds their data.
        self.stiffness = np.zeros(6)
        self.damping = np.zeros(6)
        self.set_stiffness(np.array([cfg.trans_stiffness] * 3 + [cfg.rot_stiffness] * 3))

    def set_stiffness(self, stiffness: np.ndarray, damping: np.ndarray | None = None) -> None:
        """Set K per axis (0 = force control on that axis) and derive D from it.

        D is critical on stiff axes and ``ControllerConfig.force_damping`` on force-controlled
        translation axes; ``damping`` (six values) replaces it where given (NaN: keep).
        """
        stiffness = np.asarray(stiffness, dtype=float)
        if stiffness.shape != (6,) or np.any(stiffness < 0):
            raise ValueError("stiffness needs six values >= 0")
        k_eff = np.where(stiffness > 0, stiffness, K_FORCE_REF)
        d = 2.0 * self.cfg.damping_ratio * np.sqrt(k_eff * self.mass)
        # Force-controlled translation axes use the configured force damping (>= the servo-loop
        # minimum above).
        force_axes = (stiffness == 0) & (np.arange(6) < 3)
        d[force_axes] = np.maximum(d[force_axes], self.cfg.force_damping)
        if damping is not None:
            damping = np.asarray(damping, dtype=float)
            if damping.shape != (6,) or np.any(damping <= 0):
                raise ValueError("damping needs six values > 0 (NaN: keep)")
            d = np.where(np.isnan(damping), d, damping)
        self.stiffness[:] = stiffness
        self.damping[:] = d

    def reset(self) -> None:
        self.offset[:] = 0.0
        self.velocity[:] = 0.0
        self.wrench_des[:] = 0.0

    def step(self, wrench_ext: np.ndarray, dt: float) -> np.ndarray:
        """Advance the offset by ``dt`` (semi-implicit Euler, damping implicit) and return it.

        Per axis (in C, :func:`vgs.native.admittance_step`; the arm's tick runs the same)::

            f = ((w_des - K e) + w_ext) dt
            v = (M v + f) / (D dt + M),   clipped to +-v_max
            e = e + v dt

        ``(M + D dt) v_new = M v + f``: unconditionally stable in the damping term.
        """
        native.admittance_step(self.offset, self.velocity, self.wrench_des, self.stiffness,
                               self.damping, self.mass, self.vmax,
                               np.ascontiguousarray(wrench_ext, dtype=float), dt)
        return self.offset
