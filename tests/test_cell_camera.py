"""Heightmap geometry: pixel <-> world round trip, and the peg's pose seen from above."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vgs.assembly.episode import peg_axis_from_heightmap
from vgs.config import profile
from vgs.sim.camera import Heightmap, RayCastCamera
from vgs.sim.cell import Cell


@pytest.fixture(scope="module")
def scene() -> tuple[Cell, RayCastCamera]:
    cfg = profile("paper")
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    return cell, RayCastCamera(cell.model, cfg.cell.camera)


def test_pixel_world_round_trip() -> None:
    cam = profile("paper").cell.camera
    x0 = cam.center_xy[0] - cam.extent / 2
    y0 = cam.center_xy[1] - cam.extent / 2
    hm = Heightmap(color=np.zeros((cam.size, cam.size, 3), np.uint8),
                   depth=np.zeros((cam.size, cam.size), np.float32), origin=(x0, y0),
                   pixel_size=cam.pixel_size)
    rng = np.random.default_rng(0)
    for row, col in rng.integers(0, cam.size, size=(200, 2)):
        x, y = hm.pixel_to_world(row, col)
        assert hm.world_to_pixel(x, y) == (row, col)
    # Rows run along +y, columns along +x; pixel (0, 0) is the corner (x0, y0).
    assert hm.pixel_to_world(0, 0) == pytest.approx((x0 + cam.pixel_size / 2,
                                                     y0 + cam.pixel_size / 2))
    assert hm.pixel_to_world(0, 1)[0] > hm.pixel_to_world(0, 0)[0]
    assert hm.pixel_to_world(1, 0)[1] > hm.pixel_to_world(0, 0)[1]


def test_heightmap_shape_and_peg_height(scene: tuple[Cell, RayCastCamera]) -> None:
    cell, cam = scene
    cell.reset(np.random.default_rng(1))
    hm = cam.capture(cell.data)
    size = cell.cfg.camera.size
    assert hm.color.shape == (size, size, 3) and hm.color.dtype == np.uint8
    assert hm.depth.shape == (size, size) and hm.depth.dtype == np.float32
    p, _ = cell.peg_pose()
    row, col = hm.world_to_pixel(p[0], p[1])
    assert float(hm.depth[row, col]) == pytest.approx(cell.cfg.peg.diameter, abs=0.002)


@pytest.mark.parametrize("seed", range(6))
def test_peg_centre_and_axis_from_heightmap(scene: tuple[Cell, RayCastCamera],
                                            seed: int) -> None:
    cell, cam = scene
    cell.reset(np.random.default_rng(seed))
    hm = cam.capture(cell.data)
    centre, axis, length = peg_axis_from_heightmap(hm)
    p, R = cell.peg_pose()
    true_axis = R[:2, 2] / np.linalg.norm(R[:2, 2])
    assert np.linalg.norm(centre - p[:2]) < 0.002
    angle = math.degrees(math.acos(min(1.0, abs(float(np.dot(axis, true_axis))))))
    assert angle < 2.0
    assert length == pytest.approx(cell.cfg.peg.length, abs=0.006)
