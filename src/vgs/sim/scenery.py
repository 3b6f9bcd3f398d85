"""What a person looking at the cell needs and the physics does not: a floor, table legs, a sky
and two named cameras.

:func:`add_scenery` adds them to a cell's :class:`mujoco.MjSpec`. The simulated cell
(:func:`vgs.sim.cell.build_spec`) never carries them; the exported scene
(:mod:`vgs.tools.scene`) and the renderer (:mod:`vgs.render`) do. Every geom added here
has ``contype = conaffinity = 0`` and lies in geom group 2, so it touches nothing and the
ray-cast heightmap camera (group 0 only) does not see it.

Cameras:

* ``overhead``: the heightmap camera's pinhole (``camera.center_xy`` at ``camera.height`` above
  the table, looking straight down) with a field of view that spans the heightmap's square
  (``camera.extent``) on the table. Its image has world +x to the right and +y up; the
  heightmap's rows run along +y from the top, so ``np.flipud`` of a square overhead image is in
  the heightmap's row order.
* ``perspective``: an oblique view of the robot, the peg's workspace and the hole.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from vgs.config import CellConfig
from vgs.sim.objects import TABLE_CENTER, TABLE_HALF

TABLE_HEIGHT = 0.75  # table top above the floor [m] (the table top is the world plane z = 0)
SCENERY_GROUP = 2
OVERHEAD_CAMERA = "overhead"
PERSPECTIVE_CAMERA = "perspective"
CAMERAS = (OVERHEAD_CAMERA, PERSPECTIVE_CAMERA)
# Perspective camera: where it stands and the point it looks at (world frame) [m].
PERSPECTIVE_POS = (1.2, -0.86, 0.78)
PERSPECTIVE_TARGET = (0.34, 0.03, 0.16)
PERSPECTIVE_FOVY = 40.0  # [deg]


def look_at_quat(pos: np.ndarray, target: np.ndarray,
                 up: np.ndarray | None = None) -> np.ndarray:
    """Quaternion (w, x, y, z) of a MuJoCo camera at ``pos`` looking at ``target``.

    A MuJoCo camera looks along its -z axis with +y up in the image.

    Args:
        pos: Camera position (world) [m].
        target: Point to look at (world) [m].
        up: World direction that appears up in the image (default +z).

    Returns:
        The unit quaternion of the camera frame in the world frame.
    """
    up = np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=float)
    z = np.asarray(pos, dtype=float) - np.asarray(target, dtype=float)
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.stack([x, y, z], axis=1).ravel())
    return quat


def overhead_fovy(cfg: CellConfig) -> float:
    """Vertical field of view [deg] of the ``overhead`` camera: the heightmap's square at z = 0."""
    cam = cfg.camera
    return math.degrees(2.0 * math.atan(0.5 * cam.extent / cam.height))


def add_scenery(spec: mujoco.MjSpec, cfg: CellConfig) -> None:
    """Add floor, table legs, sky, lights and the named cameras to a cell's spec.

    Args:
        spec: The spec of :func:`vgs.sim.cell.build_spec` (changed in place).
        cfg: The cell's configuration (camera placement).
    """
    spec.add_texture(name="skybox", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.55, 0.65, 0.8],
                     rgb2=[0.1, 0.12, 0.15], width=256, height=256)
    spec.add_texture(name="floor", type=mujoco.mjtTexture.mjTEXTURE_2D,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, rgb1=[0.32, 0.34, 0.36],
                     rgb2=[0.26, 0.28, 0.3], width=300, height=300)
    floor_material = spec.add_material(name="floor", texrepeat=[8, 8])
    floor_material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "floor"
    world = spec.worldbody
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3.0, 3.0, 0.05],
                   pos=[0.3, 0.0, -TABLE_HEIGHT], material="floor", contype=0, conaffinity=0,
                   group=SCENERY_GROUP)
    leg_half = 0.5 * (TABLE_HEIGHT - 2 * TABLE_HALF[2])
    for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
        x = TABLE_CENTER[0] + sx * (TABLE_HALF[0] - 0.04)
        y = TABLE_CENTER[1] + sy * (TABLE_HALF[1] - 0.04)
        world.add_geom(name=f"table_leg_{i}", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[0.025, 0.025, leg_half], pos=[x, y, -TABLE_HEIGHT + leg_half],
                       rgba=[0.4, 0.3, 0.22, 1], contype=0, conaffinity=0, group=SCENERY_GROUP)
    world.add_light(name="key_light", pos=[1.2, -1.0, 2.0], dir=[-0.5, 0.4, -1.0],
                    diffuse=[0.5, 0.5, 0.5], castshadow=False)
    spec.visual.headlight.ambient = [0.25, 0.25, 0.25]
    spec.visual.headlight.diffuse = [0.35, 0.35, 0.35]
    cam = cfg.camera
    world.add_camera(name=OVERHEAD_CAMERA, pos=[*cam.center_xy, cam.height], quat=[1, 0, 0, 0],
                     fovy=overhead_fovy(cfg))
    pos = np.array(PERSPECTIVE_POS)
    world.add_camera(name=PERSPECTIVE_CAMERA, pos=pos.tolist(),
                     quat=look_at_quat(pos, np.array(PERSPECTIVE_TARGET)).tolist(),
                     fovy=PERSPECTIVE_FOVY)
