"""Rotation helpers (3x3 matrices, axis-angle vectors).

Poses are named after their frames: ``R_world_tcp`` maps tool-frame vectors to world-frame ones.
"""

from __future__ import annotations

import math

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """``[v]_x`` with ``[v]_x w = v x w``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def exp_so3(w: np.ndarray) -> np.ndarray:
    """Rodrigues: ``exp([w]_x) = I + sin(t) K + (1 - cos t) K^2``, ``t = |w|``, ``K = [w/t]_x``.

    Written out on Python floats (with ``K^2 = u u^T - I``, ``u = w / t``): numpy's per-call
    overhead dominates on 3-vectors, and this runs several times per control tick. The matrix
    is built from its nine entries in row order (a flat tuple converts in half the time of
    nested lists).
    """
    w0, w1, w2 = w.tolist() if isinstance(w, np.ndarray) else map(float, w)
    theta = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if theta < 1e-12:
        return np.array((1.0, -w2, w1, w2, 1.0, -w0, -w1, w0, 1.0)).reshape(3, 3)
    x, y, z = w0 / theta, w1 / theta, w2 / theta
    s, c = math.sin(theta), 1.0 - math.cos(theta)
    xy, xz, yz = c * x * y, c * x * z, c * y * z
    return np.array((
        1.0 - c * (y * y + z * z), xy - s * z, xz + s * y,
        xy + s * z, 1.0 - c * (x * x + z * z), yz - s * x,
        xz - s * y, yz + s * x, 1.0 - c * (x * x + y * y),
    )).reshape(3, 3)


def log_so3(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`exp_so3`: the rotation vector ``w`` with ``exp([w]_x) = R``."""
    return np.array(log_so3_tuple(R))


def log_so3_tuple(R: np.ndarray) -> tuple[float, float, float]:
    """:func:`log_so3` as three Python floats (the controller's inner loop uses these)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    cos_t = max(-1.0, min(1.0, 0.5 * (r00 + r11 + r22 - 1.0)))
    theta = math.acos(cos_t)
    if math.pi - theta < 1e-6:
        # Near pi: axis from the largest diagonal of (R + I) / 2.
        M = 0.5 * (np.asarray(R, dtype=float) + np.eye(3))
        axis = M[:, int(np.argmax(np.diag(M)))]
        axis = theta * axis / np.linalg.norm(axis)
        return float(axis[0]), float(axis[1]), float(axis[2])
    k = 0.5 if theta < 1e-9 else theta / (2.0 * math.sin(theta))
    return k * (r21 - r12), k * (r02 - r20), k * (r10 - r01)


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def tilt_angle(axis_a: np.ndarray, axis_b: np.ndarray) -> float:
    """Unsigned angle between two lines (axes of symmetric bodies), in [0, pi/2]."""
    c = abs(float(np.dot(axis_a, axis_b)) / (np.linalg.norm(axis_a) * np.linalg.norm(axis_b)))
    return math.acos(min(1.0, c))
