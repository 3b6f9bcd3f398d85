"""The search's Archimedes spiral of touch-down points (paper 3.2).

Points on ``r = b theta`` with ``b = pitch / (2 pi)`` around a centre, about ``step`` apart
along the spiral: ``d(theta) = step / sqrt(r^2 + (2 b)^2)``, which is ``step / |dr/dtheta|``
far from the centre and half a turn from the centre to the second point. Past ``radius`` the
spiral starts at the centre again, turned by the golden angle, so that a repeated sweep touches
new points.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))  # turn of a repeated spiral [rad]


def spiral_points(center_xy: np.ndarray, pitch: float, step: float, radius: float,
                  turn: float = 0.0) -> Iterator[np.ndarray]:
    """Endless touch-down points ``(x, y)`` [m], the first at ``center_xy``.

    Args:
        center_xy: Centre of the spiral (the nominal hole) [m].
        pitch: Radial growth per turn [m].
        step: Distance between two points along the spiral [m].
        radius: Largest radius [m]; beyond it the spiral starts again, turned by the golden
            angle.
        turn: Angle of the spiral's start [rad].
    """
    if pitch <= 0 or step <= 0 or radius <= 0:
        raise ValueError("pitch, step and radius must be > 0")
    b = pitch / (2 * math.pi)
    theta = 0.0
    while True:
        r = b * theta
        if r > radius:
            theta, r = 0.0, 0.0
            turn += GOLDEN_ANGLE
        yield np.asarray(center_xy, dtype=float) + r * np.array(
            [math.cos(theta + turn), math.sin(theta + turn)])
        theta += step / math.hypot(r, 2 * b)
