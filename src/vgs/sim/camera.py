"""Overhead RGB-D camera, ray-cast (no OpenGL), reprojected to an orthographic heightmap.

A pinhole camera at ``(center_xy, height)`` looks straight down. Its depth image is ray-cast with
``mujoco.mj_multiRay`` (one ray per camera pixel through a grid that covers the workspace at
``OVERSAMPLE`` rays per heightmap cell), giving a 3-D point and the geom hit per ray. As in
Zeng et al.'s visual pushing-grasping, the point cloud is then reprojected onto an orthographic
grid: each cell keeps the highest point that falls into it (height above the table) and its
colour. Only geom group 0 (table, peg, hole block) is visible, as if the arm were moved away.

Heightmap pixel convention: row ``i`` and column ``j`` cover the world point
``x = x0 + (j + 0.5) s``, ``y = y0 + (i + 0.5) s`` with ``(x0, y0) = center - extent / 2`` and
pixel size ``s``: rows run along +y, columns along +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from vgs import native
from vgs.config import CameraConfig

OVERSAMPLE = 2
_LIGHT_NORM = math.sqrt(0.3 * 0.3 + 0.2 * 0.2 + 1.0 * 1.0)
_LIGHT = (0.3 / _LIGHT_NORM, -0.2 / _LIGHT_NORM, 1.0 / _LIGHT_NORM)  # unit light direction


@dataclass(frozen=True)
class Heightmap:
    """An orthographic RGB-D heightmap.

    Attributes:
        color: ``(H, W, 3)`` uint8 colours.
        depth: ``(H, W)`` float32 heights above the table [m].
        origin: World (x, y) of the heightmap's corner (pixel (0, 0)'s outer corner) [m].
        pixel_size: Metres per pixel.
    """

    color: np.ndarray
    depth: np.ndarray
    origin: tuple[float, float]
    pixel_size: float

    def pixel_to_world(self, row: float, col: float) -> tuple[float, float]:
        """Centre of pixel (row, col) in world x, y [m]."""
        s = self.pixel_size
        return self.origin[0] + (col + 0.5) * s, self.origin[1] + (row + 0.5) * s

    def world_to_pixel(self, x: float, y: float) -> tuple[int, int]:
        """Pixel (row, col) containing world point (x, y)."""
        s = self.pixel_size
        return int(np.floor((y - self.origin[1]) / s)), int(np.floor((x - self.origin[0]) / s))


class RayCastCamera:
    """Ray-cast RGB-D camera for a compiled model.

    Args:
        model: The compiled MuJoCo model.
        cfg: Camera configuration.
    """

    def __init__(self, model: mujoco.MjModel, cfg: CameraConfig) -> None:
        self.model = model
        self.cfg = cfg
        n = cfg.size * OVERSAMPLE
        half = cfg.extent / 2
        ticks = (np.arange(n) + 0.5) / n * cfg.extent - half
        gx, gy = np.meshgrid(ticks, ticks)
        vec = np.stack([gx.ravel(), gy.ravel(), -np.full(gx.size, cfg.height)], axis=1)
        self.vec = (vec / np.linalg.norm(vec, axis=1, keepdims=True)).ravel()
        self.nray = gx.size
        self.origin = np.array([*cfg.center_xy, cfg.height])
        self.geomid = np.zeros(self.nray, dtype=np.int32)
        self.dist = np.zeros(self.nray)
        self.normal = np.zeros(3 * self.nray)
        self.geomgroup = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
        self._depth = np.zeros(cfg.size * cfg.size)
        self._color = np.zeros((cfg.size * cfg.size, 3))

    def capture(self, data: mujoco.MjData, rng: np.random.Generator | None = None) -> Heightmap:
        """Ray-cast the scene and return its heightmap."""
        cfg = self.cfg
        mujoco.mj_multiRay(self.model, data, self.origin, self.vec, self.geomgroup, 1, -1,
                           self.geomid, self.dist, self.normal, self.nray, 10.0)
        x0 = cfg.center_xy[0] - cfg.extent / 2
        y0 = cfg.center_xy[1] - cfg.extent / 2
        # Reprojection, in C (vgs.native.heightmap_fill): each ray's point p = v d + o falls
        # into the cell (floor((y - y0) / s), floor((x - x0) / s)); a cell keeps its highest
        # point (height clipped at the table, ties to the later ray) and its colour, the geom's
        # times the Lambert shade 0.55 + 0.45 clip(n . l, 0, 1).
        depth, color = self._depth, self._color
        native.heightmap_fill(self.geomid, self.dist, self.vec, self.normal,
                              self.model.geom_rgba, (*self.origin.tolist(), x0, y0, cfg.pixel_size,
                                           *_LIGHT), cfg.size, self.model.ngeom, self.nray,
                              depth, color)
        depth = depth.reshape(cfg.size, cfg.size)
        if cfg.depth_noise > 0 and rng is not None:
            depth = np.maximum(depth + rng.normal(0.0, cfg.depth_noise, depth.shape), 0.0)
        color_u8 = (np.clip(color, 0, 1) * 255).astype(np.uint8).reshape(cfg.size, cfg.size, 3)
        return Heightmap(color=color_u8, depth=depth.astype(np.float32), origin=(x0, y0),
                         pixel_size=cfg.pixel_size)
