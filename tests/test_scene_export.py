"""The exported MJCF loads on its own and carries the servo gains and the home keyframe."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from vgs.config import override, profile
from vgs.experiments.scene import HOME_KEY, export_scene
from vgs.sim import ur5
from vgs.sim.cell import HOME_Q, Cell


def test_export_loads_with_gains_and_keyframe(tmp_path: Path) -> None:
    cfg = override(profile("paper"), "cell.peg.mass", 0.6)
    info = export_scene(cfg, tmp_path / "sub" / "scene.xml", seed=2)
    assert info.path.exists() and info.nmesh == cfg.cell.hole.segments
    model = mujoco.MjModel.from_xml_path(str(info.path))
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    assert model.nq == cell.model.nq and model.nu == cell.model.nu
    np.testing.assert_allclose(model.actuator_gainprm[:, 0], cell.model.actuator_gainprm[:, 0])
    np.testing.assert_allclose(model.actuator_biasprm[:, :3], cell.model.actuator_biasprm[:, :3])
    peg = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "peg")
    assert model.body_mass[peg] == 0.6
    # The home keyframe holds the arm still at HOME_Q.
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY,
                                                                HOME_KEY))
    mujoco.mj_step(model, data, 250)
    arm = [model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]
           for n in ur5.JOINT_NAMES]
    assert np.abs(data.qpos[arm] - HOME_Q).max() < 0.01
