"""Videos of episodes, drawn afterwards from the recorded states, and the missing-GL message."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vgs.config import profile
from vgs.render import frame_indices, gl_available
from vgs.sim.scenery import overhead_fovy
from vgs.tools.demo import demo_video, run_demo

VGS = str(Path(sys.executable).with_name("vgs"))
GL, GL_REASON = gl_available()
needs_gl = pytest.mark.skipif(not GL, reason=f"no OpenGL for MuJoCo's renderer: {GL_REASON}")


def test_frame_indices_cover_the_episode_at_the_speed() -> None:
    times = np.arange(1, 1001) * 0.01  # 10 s of ticks at 100 Hz
    idx = frame_indices(times, fps=10, speed=5.0)  # a frame every 0.5 s
    assert idx[0] == 0 and len(idx) == 20
    np.testing.assert_allclose(times[idx], 0.01 + 0.5 * np.arange(20), atol=1e-9)
    assert frame_indices(np.zeros(0), 10, 5).size == 0


def test_overhead_camera_spans_the_heightmap() -> None:
    cam = profile("paper").cell.camera
    half = np.tan(np.radians(overhead_fovy(profile("paper").cell)) / 2) * cam.height
    assert half == pytest.approx(cam.extent / 2)


@needs_gl
@pytest.mark.slow
def test_demo_video_whole_episode(tmp_path: Path) -> None:
    """The traced episode's states, drawn afterwards: one frame per speed / fps simulated
    seconds, the last frame held; mp4 and gif."""
    import imageio.v2 as imageio

    cfg = profile("smoke")
    result = run_demo(cfg, seed=3)
    assert len(result.trace.qpos) == len(result.trace.time) > 100
    path = demo_video(result, cfg.cell, tmp_path / "demo.mp4", fps=5, speed=20.0, width=160,
                      height=120, hold_s=1.0)
    reader = imageio.get_reader(path)
    frames = [f for f in reader]
    reader.close()
    duration = result.trace.time[-1] - result.trace.time[0]
    assert len(frames) == int(duration / 4.0) + 1 + 5
    assert frames[0].shape == (120, 160, 3)
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).mean() > 1  # it moved
    gif = demo_video(result, cfg.cell, tmp_path / "demo.gif", fps=5, speed=40.0, width=96,
                     height=72)
    assert gif.read_bytes()[:6] == b"GIF89a"


@pytest.mark.slow
def test_demo_video_cli_and_missing_gl(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["MUJOCO_GL"] = "glfw"  # no display: no context
    proc = subprocess.run([VGS, "demo", "--profile", "smoke", "--video", "x.mp4"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and not (tmp_path / "x.mp4").exists()
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "MUJOCO_GL" in lines[0], proc.stderr
    proc = subprocess.run([VGS, "demo", "--video", "x.avi"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and ".mp4 or .gif" in proc.stderr
    if not GL:
        pytest.skip(f"no OpenGL for MuJoCo's renderer: {GL_REASON}")
    proc = subprocess.run([VGS, "demo", "--profile", "smoke", "--seed", "3", "--video", "d.gif",
                           "--video-size", "96x72", "--video-speed", "40", "--out", "fig"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "video" in proc.stdout and (tmp_path / "d.gif").stat().st_size > 1000


@needs_gl
def test_overhead_camera_sees_what_the_heightmap_sees() -> None:
    """The ``overhead`` camera is the heightmap camera: with the robot hidden, the peg's pixels
    of its square image, flipped upside down, lie where the heightmap has them (within the
    pinhole's parallax of a 30 mm high peg, about 2 px)."""
    import mujoco

    from vgs.render import open_renderer, render_model
    from vgs.sim.camera import RayCastCamera
    from vgs.sim.cell import Cell

    cfg = profile("paper")
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(1))  # the peg 35 px below the centre row: flips show
    hm = RayCastCamera(cell.model, cfg.cell.camera).capture(cell.data)
    model = render_model(cfg.cell)
    data = mujoco.MjData(model)
    data.qpos[:] = cell.data.qpos
    data.mocap_pos[:] = cell.data.mocap_pos
    mujoco.mj_forward(model, data)
    option = mujoco.MjvOption()
    option.geomgroup[:] = 0
    option.geomgroup[0] = 1  # table, peg, hole: what the ray-cast camera sees
    size = cfg.cell.camera.size
    renderer = open_renderer(model, size, size)
    renderer.update_scene(data, camera="overhead", scene_option=option)
    image = np.flipud(renderer.render())
    renderer.close()
    red = (image[..., 0] > 120) & (image[..., 1] < 90) & (image[..., 2] < 90)
    peg = hm.depth > 0.005
    assert red.sum() > 0.5 * peg.sum()
    np.testing.assert_allclose(np.argwhere(red).mean(axis=0), np.argwhere(peg).mean(axis=0),
                               atol=3.0)
