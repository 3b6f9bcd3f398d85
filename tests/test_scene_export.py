"""The exported MJCF loads on its own, opens at home and holds still without being touched."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from vgs.config import override, profile
from vgs.sim import ur5
from vgs.sim.cell import HOME_Q, Cell
from vgs.sim.scenery import CAMERAS
from vgs.tools.scene import HOME_KEY, export_scene


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Cell]:
    cfg = override(profile("paper"), "cell.peg.mass", 0.6)
    path = tmp_path_factory.mktemp("scene") / "sub" / "scene.xml"
    info = export_scene(cfg, path)  # the command's default reset seed, 0
    assert info.path.exists() and info.nmesh == cfg.cell.hole.segments
    assert info.cameras == CAMERAS
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(0))
    return path, cell


def test_loaded_as_it_is_holds_still_for_two_seconds(exported: tuple[Path, Cell]) -> None:
    """Plain MuJoCo: MjModel from the file, a fresh MjData, 2 s of mj_step, nothing set."""
    path, cell = exported
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = data.xpos.copy()
    mujoco.mj_step(model, data, int(round(2.0 / model.opt.timestep)))
    moved = np.linalg.norm(data.xpos - start, axis=1)
    assert moved.max() < 1e-3, model.body(int(moved.argmax())).name
    # It starts where a reset puts the cell: arm at home, peg lying on the table, hole placed.
    arm = [model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]
           for n in ur5.JOINT_NAMES]
    assert np.abs(data.qpos[arm] - HOME_Q).max() < 0.01
    peg = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "peg")
    assert abs(data.xpos[peg][2] - cell.cfg.peg.radius) < 1e-3
    np.testing.assert_allclose(data.xpos[peg][:2], cell.data.xpos[cell.ids.peg_body][:2],
                               atol=1e-3)
    np.testing.assert_allclose(data.mocap_pos[0][:2], cell.hole_xy, atol=1e-6)
    assert model.body_mass[peg] == pytest.approx(0.6)


def test_joint_values_keep_their_meaning(exported: tuple[Path, Cell]) -> None:
    """qpos means in the file what it means in vgs (to the 6 digits MJCF keeps): the same
    joint angles put the TCP, flange and F/T sites and the pads at the same places."""
    path, cell = exported
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    q = cell.data.qpos.copy()
    q[cell.ids.arm_qpos] = HOME_Q + np.array([0.3, -0.2, 0.25, 0.1, -0.4, 0.7])
    q[cell.ids.finger_qpos] = 0.02
    data.qpos[:] = q
    cell.data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    mujoco.mj_kinematics(cell.model, cell.data)
    for site in ("tcp", "flange", "ft"):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        np.testing.assert_allclose(data.site_xpos[sid], cell.data.site_xpos[
            mujoco.mj_name2id(cell.model, mujoco.mjtObj.mjOBJ_SITE, site)], atol=1e-5)
    for geom in ("pad_left", "pad_right"):
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
        np.testing.assert_allclose(data.geom_xpos[gid], cell.data.geom_xpos[
            mujoco.mj_name2id(cell.model, mujoco.mjtObj.mjOBJ_GEOM, geom)], atol=1e-5)


def test_servos_hold_home_at_zero_and_follow_offsets(exported: tuple[Path, Cell]) -> None:
    """ctrl = 0 holds home; ctrl_i = q - q_home_i drives joint i to q (the UR5 gains as in
    the cell)."""
    path, cell = exported
    model = mujoco.MjModel.from_xml_path(str(path))
    arm_act = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, n)
               for n in ur5.JOINT_NAMES]
    np.testing.assert_allclose(model.actuator_gainprm[arm_act, 0],
                               cell.model.actuator_gainprm[cell.ids.arm_act, 0])
    np.testing.assert_allclose(model.actuator_biasprm[arm_act, 1:3],
                               cell.model.actuator_biasprm[cell.ids.arm_act, 1:3])
    data = mujoco.MjData(model)
    data.ctrl[arm_act[0]] = 0.2
    mujoco.mj_step(model, data, 1000)
    pan = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT,
                                              ur5.JOINT_NAMES[0])]
    assert data.qpos[pan] == pytest.approx(HOME_Q[0] + 0.2, abs=0.01)
    # The keyframe holds the same state.
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY,
                                                                HOME_KEY))
    fresh = mujoco.MjData(model)
    np.testing.assert_allclose(data.qpos, fresh.qpos, atol=1e-4)  # as rounded in the file
    assert not data.ctrl.any()


def test_creeping_peg_held_by_the_no_slip_solver(tmp_path: Path) -> None:
    """At some reset poses (seed 2) MuJoCo's soft friction lets the lying peg turn slowly
    (about 1 mm in 2 s); with the no-slip solver on, the exported scene holds still there too."""
    cfg = override(profile("paper"), "cell.sim.noslip_iterations", 1)
    info = export_scene(cfg, tmp_path / "scene.xml", seed=2)
    model = mujoco.MjModel.from_xml_path(str(info.path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = data.xpos.copy()
    mujoco.mj_step(model, data, int(round(2.0 / model.opt.timestep)))
    assert np.linalg.norm(data.xpos - start, axis=1).max() < 1e-3


def test_the_printed_control_hint_moves_the_joint_it_names(tmp_path: Path) -> None:
    """``vgs export-scene`` prints how to drive the servos in names; run as printed on the
    exported file, it turns the joint it names by the value it names, and no other arm joint
    (issue 42: actuators 0-1 are the fingers)."""
    import re
    import subprocess
    import sys

    path = tmp_path / "scene.xml"
    proc = subprocess.run([sys.executable, "-m", "vgs.cli", "export-scene", "--out", str(path)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    hint = re.search(r"(data\.actuator\('(\w+)'\)\.ctrl = ([\d.]+)) turns (\w+) ([\d.]+) rad",
                     proc.stdout)
    assert hint, proc.stdout
    code, actuator, value, joint, turn = hint.groups()
    assert actuator == joint and value == turn
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    home = {n: float(data.joint(n).qpos[0]) for n in ur5.JOINT_NAMES}
    exec(code, {"data": data})
    mujoco.mj_step(model, data, 1000)
    for name in ur5.JOINT_NAMES:
        moved = float(data.joint(name).qpos[0]) - home[name]
        assert moved == pytest.approx(float(value) if name == joint else 0.0, abs=0.01), name


def test_documented_weld_carries_the_peg(exported: tuple[Path, Cell]) -> None:
    """docs/cell.md's lines that switch the stick weld on in plain MuJoCo: the peg then keeps
    its pose relative to the gripper housing while the arm moves."""
    import re

    text = (Path(__file__).resolve().parents[1] / "docs" / "cell.md").read_text()
    (lines,) = [b for b in re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)
                if "pad_stiction" in b]
    model = mujoco.MjModel.from_xml_path(str(exported[0]))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    exec(lines, {"model": model, "data": data, "mujoco": mujoco, "np": np})

    def relative() -> np.ndarray:
        g, p = data.body("rg2"), data.body("peg")
        return g.xmat.reshape(3, 3).T @ (p.xpos - g.xpos)

    before, start = relative(), data.body("peg").xpos.copy()
    data.actuator("shoulder_lift_joint").ctrl = -0.2  # lifts the arm
    mujoco.mj_step(model, data, 1000)
    assert np.linalg.norm(data.body("peg").xpos - start) > 0.05  # carried
    np.testing.assert_allclose(relative(), before, atol=2e-3)
