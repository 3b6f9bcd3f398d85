"""Export the assembly cell as a self-contained MJCF file that is ready to open.

Loaded as it is (``mujoco.MjModel.from_xml_path`` and a fresh ``MjData``, or
``python -m mujoco.viewer --mjcf scene.xml``), the exported model starts in the cell's state
after a reset (seed ``--seed``) and holds still: the arm at home with the gripper open, the peg
resting on the table, the hole block at its displaced position. MJCF has no place for a default
state other than the model's reference configuration ``qpos0`` and no default for controls
(a fresh ``MjData`` has ``ctrl = 0``), so the exporter writes that state into the model itself:

1. The reset state is settled first: the cell is reset and stepped :data:`SETTLE_S` seconds
   with the servos holding their targets, so the arm's static deflection under the tool's
   weight and the peg's contact with the table are already in it.
2. Arm and finger joints: each joint's ``ref`` is its settled position and its body is placed
   at that position, so ``qpos0`` is the settled state while ``qpos`` keeps the meaning it has
   in vgs (UR5 DH joint angles [rad], finger travel from closed [m]).
3. The peg (free joint) and the hole block (mocap) are placed at their settled poses.
4. Servos: the eight position servos, each named after the joint it drives (``finger_left``,
   ``finger_right``, then the six UR5 joints ``shoulder_pan_joint`` ... ``wrist_3_joint``; the
   fingers come first, so address them by name, not index), take their target relative to the
   home target: ``biasprm[0] = kp * target_home`` and the control range is shifted by
   ``-target_home``, so ``ctrl = 0`` (MuJoCo's default) holds home and :data:`CONTROL_HINT`
   holds. The UR5 servo gains (``controller.joint_kp`` / ``joint_kv``, set by
   :class:`vgs.sim.cell.Cell` on the compiled model) are written too.
5. Scenery (:mod:`vgs.sim.scenery`): a floor, table legs and the cameras ``overhead`` (the
   heightmap camera) and ``perspective``; none of it touches anything.

The weld ``pad_stiction`` (gripper housing ``rg2`` to ``peg``) is written switched off: vgs
switches it in Python while the pads stick (:mod:`vgs.sim.stiction`); docs/cell.md gives the
lines that switch it on in plain MuJoCo. A keyframe ``home`` keeps the same state
(``ctrl = 0``) for ``mj_resetDataKeyframe``. The hole's wedges are meshes given by inline
vertices, so the file needs no asset files. The
written file is loaded back to check it.
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
from vgs.sim.scenery import CAMERAS, add_scenery

HOME_KEY = "home"
SETTLE_S = 1.0  # simulated seconds the reset state settles before it is written [s]
SERVO_JOINTS = (*ur5.JOINT_NAMES, "finger_left_joint", "finger_right_joint")
# How to drive the exported servos, in names (tests/test_scene_export.py runs it).
CONTROL_HINT = ("ctrl = 0 holds home; each actuator drives the joint of its name (finger_left "
                "-> finger_left_joint) to its home position plus ctrl, e.g. "
                "data.actuator('shoulder_lift_joint').ctrl = 0.2 turns shoulder_lift_joint "
                "0.2 rad from home")


@dataclass(frozen=True)
class SceneInfo:
    """What was written.

    Attributes:
        path: The MJCF file.
        nbody: Bodies of the reloaded model.
        ngeom: Geoms of the reloaded model.
        nmesh: Meshes of the reloaded model.
        nu: Actuators of the reloaded model.
        cameras: Names of the model's cameras.
    """

    path: Path
    nbody: int
    ngeom: int
    nmesh: int
    nu: int
    cameras: tuple[str, ...] = CAMERAS


def settled_state(cfg: ExperimentConfig, seed: int = 0) -> Cell:
    """A cell reset with ``seed`` and stepped :data:`SETTLE_S` seconds, the servos holding."""
    ctrl = cfg.controller
    cell = Cell(cfg.cell, ctrl.joint_kp, ctrl.joint_kv)
    cell.reset(np.random.default_rng(seed))
    cell.step(int(round(SETTLE_S / cfg.cell.sim.timestep)))
    return cell


def _place_at(body: mujoco.MjsBody, joint: mujoco.MjsJoint, q: float) -> None:
    """Move ``body``'s frame to where joint value ``q`` puts it and make ``q`` the joint's
    reference, so the geometry at any joint value is unchanged and ``qpos0 = q``."""
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(body.quat, dtype=float))
    R = R.reshape(3, 3)
    axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    delta = q - joint.ref
    if joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
        body.pos = (np.asarray(body.pos) + R @ (axis * delta)).tolist()
    else:
        rot_q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(rot_q, axis, delta)
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, rot_q)
        anchor = np.asarray(joint.pos, dtype=float)
        body.pos = (np.asarray(body.pos) + R @ (anchor - rot.reshape(3, 3) @ anchor)).tolist()
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, np.asarray(body.quat, dtype=float), rot_q)
        body.quat = (quat / np.linalg.norm(quat)).tolist()
    joint.ref = q


def scene_xml(cfg: ExperimentConfig, seed: int = 0) -> str:
    """MJCF text of the cell of ``cfg`` whose default state is the settled reset of ``seed``.

    Args:
        cfg: Experiment configuration (cell and controller gains).
        seed: Seed of the reset that sets the peg pose and the hole position.

    Returns:
        The MJCF document.
    """
    ctrl = cfg.controller
    cell = settled_state(cfg, seed)
    m, d = cell.model, cell.data
    spec = mujoco.MjSpec.from_string(cell.export_xml())
    add_scenery(spec, cfg.cell)
    gains = dict(zip(ur5.JOINT_NAMES, zip(ctrl.joint_kp, ctrl.joint_kv, strict=True),
                     strict=True))
    for act in spec.actuators:
        if act.name in gains:
            kp, kv = gains[act.name]
            act.gainprm[0] = kp
            act.biasprm[1] = -kp
            act.biasprm[2] = -kv
        a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, act.name)
        target = float(d.ctrl[a])
        act.biasprm[0] = act.gainprm[0] * target
        act.ctrlrange = [act.ctrlrange[0] - target, act.ctrlrange[1] - target]
    for name in SERVO_JOINTS:
        joint = spec.joint(name)
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        _place_at(spec.body(m.body(m.jnt_bodyid[j]).name), joint, float(d.qpos[m.jnt_qposadr[j]]))
    peg = spec.body("peg")
    peg.pos = d.xpos[cell.ids.peg_body].tolist()
    peg.quat = d.xquat[cell.ids.peg_body].tolist()
    spec.body("hole").pos = d.mocap_pos[cell.ids.hole_mocap].tolist()
    spec.add_key(name=HOME_KEY, qpos=d.qpos.tolist(), qvel=np.zeros(m.nv).tolist(),
                 ctrl=np.zeros(m.nu).tolist(), mpos=d.mocap_pos.ravel().tolist(),
                 mquat=d.mocap_quat.ravel().tolist())
    return spec.to_xml()


def export_scene(cfg: ExperimentConfig, path: str | Path, seed: int = 0) -> SceneInfo:
    """Write the cell of ``cfg`` to ``path`` and check that MuJoCo loads the file.

    Args:
        cfg: Experiment configuration.
        path: Output MJCF file; parent folders are created.
        seed: Seed of the reset written as the default state (and keyframe ``home``).

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
    cameras = tuple(model.camera(i).name for i in range(model.ncam))
    return SceneInfo(path=path, nbody=model.nbody, ngeom=model.ngeom, nmesh=model.nmesh,
                     nu=model.nu, cameras=cameras)
