"""The per-tick kernels in C (``vgs.native``) against the plain Python and numpy they replaced:
the same bits, not merely close values (the golden records hold whole episodes; these hold each
kernel on inputs no golden episode reaches)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from vgs import native
from vgs import vecmath as vm
from vgs.config import ControllerConfig, profile
from vgs.control.admittance import Admittance
from vgs.control.robot import Robot
from vgs.sim.camera import _LIGHT, RayCastCamera
from vgs.sim.cell import Cell


def _admittance_reference(e: list[float], v: list[float], wd: list[float], K: list[float],
                          D: list[float], M: list[float], vmax: list[float], w: list[float],
                          dt: float) -> None:
    """Admittance.step as it was written on Python floats."""
    den = [d * dt + m for d, m in zip(D, M, strict=True)]
    for i in range(6):
        vi = (v[i] * M[i] + ((wd[i] - K[i] * e[i]) + w[i]) * dt) / den[i]
        vi = max(min(vi, vmax[i]), -vmax[i])
        v[i] = vi
        e[i] = e[i] + vi * dt


def test_the_admittance_step_gives_the_python_floats_bits() -> None:
    rng = np.random.default_rng(7)
    adm = Admittance(ControllerConfig())
    for trial in range(200):
        adm.set_stiffness(rng.choice([0.0, 1.0], 6) * rng.uniform(10.0, 3e4, 6))
        adm.offset[:] = rng.normal(0.0, 1e-3, 6)
        adm.velocity[:] = rng.normal(0.0, 1e-2, 6) * (trial % 3)  # some clip, some do not
        adm.wrench_des[:] = rng.normal(0.0, 5.0, 6)
        w = rng.normal(0.0, 20.0, 6)
        e, v = adm.offset.tolist(), adm.velocity.tolist()
        _admittance_reference(e, v, adm.wrench_des.tolist(), adm.stiffness.tolist(),
                              adm.damping.tolist(), adm.mass.tolist(), adm.vmax.tolist(),
                              w.tolist(), 0.01)
        adm.step(w, 0.01)
        assert adm.offset.tolist() == e and adm.velocity.tolist() == v


def test_the_commanded_pose_is_vecmaths_rodrigues_to_the_bit() -> None:
    cfg = profile("quick")
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(0))
    mujoco.mj_forward(cell.model, cell.data)
    arm = Robot(cell, cfg.controller, np.random.default_rng(0)).arm
    rng = np.random.default_rng(3)
    for scale in (0.0, 1e-13, 1e-6, 1e-2, 1.0, 3.0):
        arm.admittance.offset[:] = rng.normal(0.0, 1.0, 6) * scale
        R_ref = vm.mm(vm.exp_so3(tuple(rng.normal(0.0, 1.0, 3).tolist())), vm.rot_z(0.3))
        arm.set_reference(tuple(rng.normal(0.0, 0.3, 3).tolist()), R_ref)
        p, R = arm.commanded_t()
        e = arm.admittance.offset.tolist()
        assert p == tuple(a + b for a, b in zip(arm.reference_t[0], e[:3], strict=True))
        want = R_ref if e[3:] == [0.0, 0.0, 0.0] else vm.mm(vm.exp_so3(e[3:]), R_ref)
        assert R == want


def _reprojection_reference(camera: RayCastCamera) -> tuple[np.ndarray, np.ndarray]:
    """The heightmap's reprojection as numpy did it before the C (after ``mj_multiRay``)."""
    cfg = camera.cfg
    hit = np.flatnonzero(camera.geomid >= 0)
    pts = camera.vec.reshape(-1, 3)[hit]
    pts *= camera.dist[hit, None]
    pts += camera.origin
    x0 = cfg.center_xy[0] - cfg.extent / 2
    y0 = cfg.center_xy[1] - cfg.extent / 2
    col = np.floor((pts[:, 0] - x0) / cfg.pixel_size).astype(int)
    row = np.floor((pts[:, 1] - y0) / cfg.pixel_size).astype(int)
    ok = np.flatnonzero((row >= 0) & (row < cfg.size) & (col >= 0) & (col < cfg.size))
    rays = hit[ok]
    n = camera.normal.reshape(-1, 3)[rays]
    lit = n[:, 0] * _LIGHT[0] + n[:, 1] * _LIGHT[1] + n[:, 2] * _LIGHT[2]
    shade = 0.55 + 0.45 * np.clip(lit, 0.0, 1.0)
    rgb = camera.model.geom_rgba[camera.geomid[rays], :3] * shade[:, None]
    z = np.maximum(pts[ok, 2], 0.0)
    flat = row[ok] * cfg.size + col[ok]
    order = np.argsort(z, kind="stable")  # the highest point per cell: the last write wins
    depth = np.zeros(cfg.size * cfg.size)
    color = np.zeros((cfg.size * cfg.size, 3))
    depth[flat[order]] = z[order]
    color[flat[order]] = rgb[order]
    return depth, color


@pytest.mark.parametrize("name", ["quick", "paper"])
def test_the_heightmap_reprojection_gives_numpys_bits(name: str) -> None:
    cfg = profile(name)
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    camera = RayCastCamera(cell.model, cfg.cell.camera)
    for seed in range(4):
        cell.reset(np.random.default_rng(seed))
        mujoco.mj_forward(cell.model, cell.data)
        hm = camera.capture(cell.data)  # leaves the rays of this scene in the camera
        depth, color = _reprojection_reference(camera)
        assert camera._depth.tobytes() == depth.tobytes()
        assert camera._color.tobytes() == color.tobytes()
        assert np.count_nonzero(hm.depth > 0.01) > 50  # the peg is in view


def test_the_kernels_refuse_arrays_of_the_wrong_kind() -> None:
    z = np.zeros(6)
    with pytest.raises(ValueError, match="offset"):
        native.admittance_step(np.zeros(6, dtype=np.float32), z, z, z, z, z, z, z, 0.01)
    with pytest.raises(ValueError, match="wrench"):
        native.admittance_step(z, z, z, z, z, z, z, np.zeros(5), 0.01)
