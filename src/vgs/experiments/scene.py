"""Export the compiled assembly cell as a self-contained MJCF file for MuJoCo's own viewer.

:meth:`vgs.sim.cell.Cell.export_xml` writes the model as it was specified. Two things of the
running cell live only in the compiled model, so they are added here before writing:

* the UR5 joint servo gains (``controller.joint_kp`` / ``joint_kv``), which :class:`Cell` sets
  on the compiled model; without them the exported arm servos would have a stiffness of 1;
* a keyframe ``home`` with the state after :meth:`Cell.reset`: the arm at ``HOME_Q`` with the
  gripper open, the peg lying on the table and the hole block at its (displaced) position.

The hole's wedges are meshes given by inline vertices, so the file needs no asset files. The
written file is loaded back with ``mujoco.MjModel.from_xml_path`` to check it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from vgs.config import ExperimentConfig
from vgs.errors import SimulationError
from vgs.sim import ur5
from vgs.sim.cell import Cell

HOME_KEY = "home"


@dataclass(frozen=True)
class SceneInfo:
    """What was written.

    Attributes:
        path: The MJCF file.
        nbody: Bodies of the reloaded model.
        ngeom: Geoms of the reloaded model.
        nmesh: Meshes of the reloaded model.
        nu: Actuators of the reloaded model.
    """

    path: Path
    nbody: int
    ngeom: int
    nmesh: int
    nu: int


def scene_xml(cfg: ExperimentConfig, seed: int = 0) -> str:
    """MJCF text of the cell of ``cfg`` with servo gains and the ``home`` keyframe.

    Args:
        cfg: Experiment configuration (cell and controller gains).
        seed: Seed of the reset that sets the keyframe's peg pose and hole position.

    Returns:
        The MJCF document.
    """
    ctrl = cfg.controller
    cell = Cell(cfg.cell, ctrl.joint_kp, ctrl.joint_kv)
    cell.reset(np.random.default_rng(seed))
    spec = mujoco.MjSpec.from_string(cell.export_xml())
    for name, kp, kv in zip(ur5.JOINT_NAMES, ctrl.joint_kp, ctrl.joint_kv, strict=True):
        act = spec.actuator(name)
        act.gainprm[0] = kp
        act.biasprm[1] = -kp
        act.biasprm[2] = -kv
    d = cell.data
    spec.add_key(name=HOME_KEY, qpos=d.qpos.tolist(), qvel=d.qvel.tolist(),
                 ctrl=d.ctrl.tolist(), mpos=d.mocap_pos.ravel().tolist(),
                 mquat=d.mocap_quat.ravel().tolist())
    return spec.to_xml()


def export_scene(cfg: ExperimentConfig, path: str | Path, seed: int = 0) -> SceneInfo:
    """Write the cell of ``cfg`` to ``path`` and check that MuJoCo loads the file.

    Args:
        cfg: Experiment configuration.
        path: Output MJCF file; parent folders are created.
        seed: Seed of the reset stored as the ``home`` keyframe.

    Returns:
        Sizes of the reloaded model.

    Raises:
        SimulationError: If MuJoCo cannot load the written file.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene_xml(cfg, seed))
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise SimulationError(f"the exported scene {path} does not load: {exc}") from exc
    return SceneInfo(path=path, nbody=model.nbody, ngeom=model.ngeom, nmesh=model.nmesh,
                     nu=model.nu)
