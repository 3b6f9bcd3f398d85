"""The peg as the robot perceives it in a heightmap: its principal axis.

One owner for the perception both the centre heuristic (:func:`vgs.assembly.episode.
peg_axis_from_heightmap`, in world metres) and the paper's position action
(:func:`vgs.grasping.actions.perceived_jaw_angle`, in pixels) use. The peg lies on the table,
so the pixels above it form a thin bar; its long direction is the eigenvector of the points'
covariance with the largest eigenvalue,

    c = mean(p_n),   C = [[a, b], [b, d]] = cov(p_n - c),   C u = lambda_max u,

    lambda_max = (a + d) / 2 + sqrt(((a - d) / 2)^2 + b^2),
    u ~ (lambda_max - d, b)  if a >= d,  else  (b, lambda_max - a),

and its visible length is the extent of the points along ``u`` (plus one pixel). The sign of
``u`` is fixed: its x component positive (or, if zero, its y component).

Written so that the bits do not depend on the CPU: element-wise numpy (one rounding per
element), sums with :func:`math.fsum` (correctly rounded) and the 2x2 eigenproblem in closed
form with IEEE square roots, no BLAS or LAPACK. NumPy and the standard library only, no vgs
imports: the grasping package (arrays only) and the assembly package both import it.
"""

from __future__ import annotations

import math

import numpy as np

PEG_PIXEL_HEIGHT = 0.005  # heightmap cells higher than this belong to the object [m]
MIN_PEG_PIXELS = 10  # fewer object pixels than this: no object in view


def principal_axis(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid, unit principal axis and extent along it of 2-D points (N, 2).

    Args:
        points: Point coordinates, (N, 2), N >= 2.

    Returns:
        ``(center (2,), axis (2,), extent)`` with ``extent = max(p . u) - min(p . u)`` over
        the centred points.
    """
    points = np.asarray(points, dtype=float)
    n = len(points)
    xs, ys = points[:, 0], points[:, 1]
    cx, cy = math.fsum(xs.tolist()) / n, math.fsum(ys.tolist()) / n
    dx, dy = xs - cx, ys - cy
    a = math.fsum((dx * dx).tolist()) / (n - 1)
    b = math.fsum((dx * dy).tolist()) / (n - 1)
    d = math.fsum((dy * dy).tolist()) / (n - 1)
    half = 0.5 * (a - d)
    lam = 0.5 * (a + d) + math.sqrt(half * half + b * b)
    ux, uy = (lam - d, b) if a >= d else (b, lam - a)
    length = math.sqrt(ux * ux + uy * uy)
    if length == 0.0:  # isotropic: any direction is principal
        ux, uy, length = 1.0, 0.0, 1.0
    ux, uy = ux / length, uy / length
    if ux < 0.0 or (ux == 0.0 and uy < 0.0):
        ux, uy = -ux, -uy
    proj = dx * ux + dy * uy
    return np.array([cx, cy]), np.array([ux, uy]), float(proj.max() - proj.min())
