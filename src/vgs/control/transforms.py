"""Rotation helpers on numpy arrays (3x3 matrices, axis-angle vectors), for callers outside the
per-tick path; each is :mod:`vgs.vecmath`'s plain-float routine, so the bits do not depend on
the CPU's BLAS kernel.

Poses are named after their frames: ``R_world_tcp`` maps tool-frame vectors to world-frame ones.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vgs import vecmath as vm


def skew(v: np.ndarray) -> np.ndarray:
    """``[v]_x`` with ``[v]_x w = v x w``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def exp_so3(w: np.ndarray | Sequence[float]) -> np.ndarray:
    """Rodrigues: ``exp([w]_x)`` as a 3x3 array (:func:`vgs.vecmath.exp_so3`)."""
    return vm.array3(vm.exp_so3(w))


def log_so3(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`exp_so3`: the rotation vector ``w`` with ``exp([w]_x) = R``."""
    return np.array(vm.log_so3(vm.mat3(R)))


def log_so3_tuple(R: np.ndarray) -> tuple[float, float, float]:
    """:func:`log_so3` as three Python floats."""
    return vm.log_so3(vm.mat3(R))


def matmul(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A B`` of two 3x3 arrays, in plain floats (:func:`vgs.vecmath.mm`)."""
    return vm.array3(vm.mm(vm.mat3(A), vm.mat3(B)))


def rot_x(a: float) -> np.ndarray:
    return vm.array3(vm.rot_x(a))


def rot_y(a: float) -> np.ndarray:
    return vm.array3(vm.rot_y(a))


def rot_z(a: float) -> np.ndarray:
    return vm.array3(vm.rot_z(a))


def tilt_angle(axis_a: np.ndarray, axis_b: np.ndarray) -> float:
    """Unsigned angle between two lines (axes of symmetric bodies), in [0, pi/2]."""
    a, b = vm.vec3(axis_a), vm.vec3(axis_b)
    c = abs(vm.dot(a, b) / (vm.norm(a) * vm.norm(b)))
    return math.acos(min(1.0, c))
