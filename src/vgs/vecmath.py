"""Plain-float maths on 3-vectors and 3x3 rotations: the same bits on every IEEE-754 machine.

The per-tick maths of the state machine runs here, and the kernels in C (``_native.c``: the
arm's tick, the pads' latch, the grasp watch) follow these formulas in the same order; none of
it runs in numpy's products: numpy sends ``@``, ``np.dot`` and ``np.linalg.norm`` to OpenBLAS,
whose kernels (chosen per CPU, or by ``OPENBLAS_CORETYPE``) sum in other orders and with or
without fused multiply-adds, and a contact-rich episode amplifies the last bit into another
episode. CPython rounds once per operation on every IEEE machine, and each function below fixes
its order of operations, so a result depends on its inputs alone.

Conventions: a vector is a tuple ``(x, y, z)``; a matrix is a flat row-major 9-tuple
``(r00, r01, r02, r10, ..., r22)`` (a flat tuple unpacks in one step). Poses are named after
their frames: ``R_world_tcp`` maps tool-frame vectors to world-frame ones.

    mv(R, v)    = R v              (row i: r_i0 v_0 + r_i1 v_1 + r_i2 v_2, summed left to right)
    mtv(R, v)   = R^T v
    mm(A, B)    = A B
    mmt(A, B)   = A B^T
    exp_so3(w)  = I + sin(t) K + (1 - cos t) K^2,  t = |w|,  K = [w / t]_x   (Rodrigues)
    log_so3(R)  = the rotation vector w with exp_so3(w) = R

No vgs imports: every package may use it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]

def mat3(R: np.ndarray | Sequence[float]) -> Mat3:
    """A 3x3 array (or anything with nine entries in row order) as a flat 9-tuple."""
    if isinstance(R, np.ndarray):
        return tuple(R.ravel().tolist())  # type: ignore[return-value]
    return tuple(float(x) for x in R)  # type: ignore[return-value]


def vec3(v: np.ndarray | Sequence[float]) -> Vec3:
    """A 3-vector as a tuple of Python floats."""
    if isinstance(v, np.ndarray):
        return tuple(v.tolist())  # type: ignore[return-value]
    return (float(v[0]), float(v[1]), float(v[2]))


def array3(R: Mat3) -> np.ndarray:
    """A flat 9-tuple as a 3x3 array (exact: a copy of the floats)."""
    return np.array(R).reshape(3, 3)


def column(R: Mat3, j: int) -> Vec3:
    """Column ``j`` of ``R``: the frame's ``j``-th axis in the outer frame."""
    return (R[j], R[3 + j], R[6 + j])


def transpose(R: Mat3) -> Mat3:
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    return (r00, r10, r20, r01, r11, r21, r02, r12, r22)


def mv(R: Mat3, v: Sequence[float]) -> Vec3:
    """``R v``."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    x, y, z = v
    return (r00 * x + r01 * y + r02 * z, r10 * x + r11 * y + r12 * z,
            r20 * x + r21 * y + r22 * z)


def mtv(R: Mat3, v: Sequence[float]) -> Vec3:
    """``R^T v``."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    x, y, z = v
    return (r00 * x + r10 * y + r20 * z, r01 * x + r11 * y + r21 * z,
            r02 * x + r12 * y + r22 * z)


def mm(A: Mat3, B: Mat3) -> Mat3:
    """``A B``."""
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = A
    b00, b01, b02, b10, b11, b12, b20, b21, b22 = B
    return (a00 * b00 + a01 * b10 + a02 * b20, a00 * b01 + a01 * b11 + a02 * b21,
            a00 * b02 + a01 * b12 + a02 * b22,
            a10 * b00 + a11 * b10 + a12 * b20, a10 * b01 + a11 * b11 + a12 * b21,
            a10 * b02 + a11 * b12 + a12 * b22,
            a20 * b00 + a21 * b10 + a22 * b20, a20 * b01 + a21 * b11 + a22 * b21,
            a20 * b02 + a21 * b12 + a22 * b22)


def mmt(A: Mat3, B: Mat3) -> Mat3:
    """``A B^T`` (the same operations, in the same order, as ``mm(A, transpose(B))``)."""
    return mm(A, transpose(B))


def mtm(A: Mat3, B: Mat3) -> Mat3:
    """``A^T B``."""
    return mm(transpose(A), B)


def dot(a: Sequence[float], b: Sequence[float]) -> float:
    """``a . b`` for 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    """``a x b``."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def norm(v: Sequence[float]) -> float:
    """Euclidean length of a 2- or 3-vector: ``sqrt(sum v_i^2)`` (IEEE sqrt is exact-rounded)."""
    if len(v) == 2:
        return math.sqrt(v[0] * v[0] + v[1] * v[1])
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def add(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(s: float, v: Sequence[float]) -> Vec3:
    return (s * v[0], s * v[1], s * v[2])


def exp_so3(w: Sequence[float]) -> Mat3:
    """Rodrigues: ``exp([w]_x) = I + sin(t) K + (1 - cos t) K^2``, ``t = |w|``,
    ``K = [w/t]_x``, written with ``K^2 = u u^T - I``, ``u = w / t``."""
    w0, w1, w2 = float(w[0]), float(w[1]), float(w[2])
    theta = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if theta < 1e-12:
        return (1.0, -w2, w1, w2, 1.0, -w0, -w1, w0, 1.0)
    x, y, z = w0 / theta, w1 / theta, w2 / theta
    s, c = math.sin(theta), 1.0 - math.cos(theta)
    xy, xz, yz = c * x * y, c * x * z, c * y * z
    return (1.0 - c * (y * y + z * z), xy - s * z, xz + s * y,
            xy + s * z, 1.0 - c * (x * x + z * z), yz - s * x,
            xz - s * y, yz + s * x, 1.0 - c * (x * x + y * y))


def log_so3(R: Mat3) -> Vec3:
    """Inverse of :func:`exp_so3`: the rotation vector ``w`` with ``exp([w]_x) = R``.

    ``theta = acos((tr R - 1) / 2)``; away from pi, ``w = theta / (2 sin theta)
    (r21 - r12, r02 - r20, r10 - r01)``; near pi the axis is the largest column of
    ``(R + I) / 2``, scaled to ``theta``.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    cos_t = max(-1.0, min(1.0, 0.5 * (r00 + r11 + r22 - 1.0)))
    theta = math.acos(cos_t)
    if math.pi - theta < 1e-6:
        diag = (0.5 * (r00 + 1.0), 0.5 * (r11 + 1.0), 0.5 * (r22 + 1.0))
        j = max(range(3), key=lambda i: diag[i])
        axis = (0.5 * (R[j] + (1.0 if j == 0 else 0.0)),
                0.5 * (R[3 + j] + (1.0 if j == 1 else 0.0)),
                0.5 * (R[6 + j] + (1.0 if j == 2 else 0.0)))
        n = norm(axis)
        return (theta * axis[0] / n, theta * axis[1] / n, theta * axis[2] / n)
    k = 0.5 if theta < 1e-9 else theta / (2.0 * math.sin(theta))
    return (k * (r21 - r12), k * (r02 - r20), k * (r10 - r01))


def rot_x(a: float) -> Mat3:
    c, s = math.cos(a), math.sin(a)
    return (1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)


def rot_y(a: float) -> Mat3:
    c, s = math.cos(a), math.sin(a)
    return (c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)


def rot_z(a: float) -> Mat3:
    c, s = math.cos(a), math.sin(a)
    return (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
