"""The peg as the robot perceives it in a heightmap: its principal axis.

One owner for the perception both the centre heuristic (:func:`vgs.assembly.episode.
peg_axis_from_heightmap`, in world metres) and the paper's position action
(:func:`vgs.grasping.actions.perceived_jaw_angle`, in pixels) use. The peg lies on the table,
so the pixels above it form a thin bar; its long direction is the eigenvector of the points'
covariance with the largest eigenvalue,

    c = mean(p_n),   C = cov(p_n - c),   C a = lambda_max a,

and its visible length is the extent of the points along ``a`` (plus one pixel). The sign of
``a`` is whatever the eigensolver gives: a two-finger grasp is symmetric.

NumPy-only, no vgs imports: the grasping package (arrays only) and the assembly package both
import it.
"""

from __future__ import annotations

import numpy as np

PEG_PIXEL_HEIGHT = 0.005  # heightmap cells higher than this belong to the object [m]
MIN_PEG_PIXELS = 10  # fewer object pixels than this: no object in view


def principal_axis(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid, unit principal axis and extent along it of 2-D points (N, 2).

    Args:
        points: Point coordinates, (N, 2), N >= 2.

    Returns:
        ``(center (2,), axis (2,), extent)`` with ``extent = max(p . a) - min(p . a)`` over
        the centred points.
    """
    center = points.mean(axis=0)
    cov = np.cov((points - center).T)
    evals, evecs = np.linalg.eigh(cov)
    axis = evecs[:, int(np.argmax(evals))]
    proj = (points - center) @ axis
    return center, axis, float(proj.max() - proj.min())
