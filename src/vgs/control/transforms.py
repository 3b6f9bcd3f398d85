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
    """Rodrigues: ``exp([w]_x) = I + sin(t) K + (1 - cos t) K^2``, ``t = |w|``, ``K = [w/t]_x``."""
    theta = float(np.linalg.norm(w))
    if theta < 1e-12:
        return np.eye(3) + skew(w)
    K = skew(w / theta)
    return np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * (K @ K)


def log_so3(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`exp_so3`: the rotation vector ``w`` with ``exp([w]_x) = R``."""
    cos_t = max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0)))
    theta = math.acos(cos_t)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if theta < 1e-9:
        return 0.5 * v
    if math.pi - theta < 1e-6:
        # Near pi: axis from the largest diagonal of (R + I) / 2.
        M = 0.5 * (R + np.eye(3))
        axis = M[:, int(np.argmax(np.diag(M)))]
        axis = axis / np.linalg.norm(axis)
        return theta * axis
    return theta / (2.0 * math.sin(theta)) * v


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
