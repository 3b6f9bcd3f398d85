"""The pixel-wise action spaces without torch: jaw angles and the peg mask.

``network.action = "position"`` (the paper's): a grasp action is a pixel (row, col) of the
heightmap; the jaws close across the peg's axis as the robot perceives it in the same heightmap,
along :func:`perceived_jaw_angle`. ``"rotation"`` (visual-pushing-grasping's): a pixel and a
rotation index ``k`` of ``R``; the jaws close along ``theta_k = 2 pi k / R``. Angles are
measured in pixel axes (column right, row down), which are world (x, y). These helpers are kept
free of torch so that processes which only run heuristic policies (evaluation workers of the
centre and random policies) start without importing it.
"""

from __future__ import annotations

import math

import numpy as np

from vgs.errors import ConfigError
from vgs.perception import MIN_PEG_PIXELS, PEG_PIXEL_HEIGHT, principal_axis


def rotation_angle(k: int, num_rotations: int) -> float:
    """Angle theta_k = 2 * pi * k / R of rotation index k [rad].

    Raises:
        ConfigError: ``network.rotation`` if k is not in [0, R).
    """
    if num_rotations < 1:
        raise ConfigError("network.num_rotations", "must be >= 1")
    if not 0 <= k < num_rotations:
        raise ConfigError("network.rotation", f"index {k} outside [0, {num_rotations})")
    return 2.0 * math.pi * k / num_rotations


def jaw_axis(k: int, num_rotations: int) -> tuple[float, float]:
    """Closing direction (d_col, d_row) = (cos theta_k, sin theta_k) of rotation k in pixels.

    Pixel coordinates have the column axis to the right and the row axis downward; the gripper
    is symmetric, so k and k + R/2 describe the same physical grasp.
    """
    theta = rotation_angle(k, num_rotations)
    return math.cos(theta), math.sin(theta)


def check_depth(depth: np.ndarray) -> None:
    """Raise :class:`ConfigError` (``heightmap.depth``) unless ``depth`` is a finite float (H, W)
    array."""
    if not isinstance(depth, np.ndarray) or not np.issubdtype(depth.dtype, np.floating):
        raise ConfigError("heightmap.depth", "must be a numpy float array")
    if depth.ndim != 2:
        raise ConfigError("heightmap.depth", f"must have shape (H, W), got {depth.shape}")
    if not np.all(np.isfinite(depth)):
        raise ConfigError("heightmap.depth", "contains NaN or infinite heights")


def perceived_jaw_angle(depth: np.ndarray) -> float:
    """Closing direction of jaws that close across the peg's perceived axis [rad].

    The peg's axis ``a = (a_col, a_row)`` is the principal axis of the object pixels
    (:func:`vgs.perception.principal_axis`, the perception of the centre heuristic, here in
    pixel units); the jaws close perpendicular to it,

        theta = atan2(a_row, a_col) + pi / 2,

    in pixel axes, which are world (x, y). ``0`` when fewer than 10 pixels show an object.
    The angle depends on the heightmap alone, so the decision and every later replay of the
    same map turn the network's input alike.
    """
    check_depth(depth)
    rows, cols = np.nonzero(depth > PEG_PIXEL_HEIGHT)
    if rows.size < MIN_PEG_PIXELS:
        return 0.0
    _, axis, _ = principal_axis(np.stack([cols, rows], axis=1).astype(np.float64))
    return math.atan2(float(axis[1]), float(axis[0])) + math.pi / 2


def closing_angle(action: str, rotation: int, num_rotations: int, depth: np.ndarray) -> float:
    """Closing direction [rad] of an action's jaws in pixel axes: across the peg's perceived
    axis for the ``position`` action (:func:`perceived_jaw_angle`), theta_k of rotation k for
    the ``rotation`` action (:func:`rotation_angle`)."""
    if action == "position":
        return perceived_jaw_angle(depth)
    return rotation_angle(rotation, num_rotations)


def peg_mask(depth: np.ndarray, min_height: float = PEG_PIXEL_HEIGHT) -> np.ndarray:
    """Pixels on the object: height above the table strictly greater than ``min_height``.

    Args:
        depth: Height above the table [m], float (H, W).
        min_height: Threshold [m]; must be >= 0.

    Returns:
        Boolean array (H, W).

    Raises:
        ConfigError: ``heightmap.depth`` on a bad map, ``peg_mask.min_height`` if negative.
    """
    check_depth(depth)
    if not (np.isfinite(min_height) and min_height >= 0):
        raise ConfigError("peg_mask.min_height", f"must be >= 0, got {min_height!r}")
    return np.asarray(depth > min_height, dtype=bool)
