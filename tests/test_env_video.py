"""Issue 42: the env on a headless machine and its videos. Gymnasium's and Stable-Baselines3's
checkers pass with ``MUJOCO_GL`` and ``DISPLAY`` unset (in a clean subprocess: conftest.py
sets ``MUJOCO_GL=egl`` for this process), rendering included; ``render_mode="rgb_array_list"``
gives the frames of the whole grasp and assembly, so that ``RecordVideo`` records the
episode."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vgs.render import gl_available

GL, GL_REASON = gl_available()
needs_gl = pytest.mark.skipif(not GL, reason=f"no OpenGL for MuJoCo's renderer: {GL_REASON}")
SMALL = {"cell.camera.size": 64, "cell.camera.pixel_size": 0.007}

CHECKERS = f"""
import warnings
warnings.simplefilter("error")
import mujoco  # imported before vgs: vgs still picks EGL for its renderer
import gymnasium
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env
import vgs

env = gymnasium.make(vgs.ENV_ID, cfg="smoke", overrides={SMALL!r})
check_env(env.unwrapped)  # renders every render mode
sb3_check_env(env.unwrapped, warn=True)
print("checked")
"""


def headless_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items()
            if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}


@needs_gl
@pytest.mark.slow
def test_checkers_pass_headless_with_no_backend_chosen() -> None:
    proc = subprocess.run([sys.executable, "-c", CHECKERS], capture_output=True, text=True,
                          timeout=600, env=headless_env())
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "checked" and proc.stderr.strip() == ""


@needs_gl
@pytest.mark.slow
def test_record_video_records_the_whole_episode(tmp_path: Path) -> None:
    pytest.importorskip("moviepy")
    import gymnasium
    from gymnasium.wrappers import RecordVideo

    import vgs

    env = RecordVideo(gymnasium.make(vgs.ENV_ID, cfg="smoke", overrides=SMALL,
                                     render_mode="rgb_array_list", render_width=160,
                                     render_height=120), str(tmp_path / "videos"))
    _, info = env.reset(seed=0)
    assert len(env.unwrapped.render()) == 1  # the peg on the table
    rows, cols = np.nonzero(info["action_mask"])
    _, _, _, _, info = env.step((0, int(rows.mean()), int(cols.mean())))
    frames = env.unwrapped.render()
    # one frame every render_speed / render_fps = 4 / 15 simulated seconds
    expected = int(info["record"]["assembly_time_s"] / (4 / 15))
    assert len(frames) >= expected > 50 and frames[0].shape == (120, 160, 3)
    assert not np.array_equal(frames[0], frames[-1])  # the peg moved
    env.render()  # hands RecordVideo the list
    assert len(env.recorded_frames) > 50
    env.close()
    (video,) = (tmp_path / "videos").glob("*.mp4")
    assert video.stat().st_size > 10_000


@needs_gl
@pytest.mark.slow
def test_documented_record_video_recipe_runs(tmp_path: Path, monkeypatch) -> None:
    """docs/agents.md's RecordVideo recipe (the ``py`` block), as written."""
    pytest.importorskip("moviepy")
    import re

    text = (Path(__file__).resolve().parents[1] / "docs" / "agents.md").read_text()
    (recipe,) = re.findall(r"```py\n(.*?)```", text, flags=re.DOTALL)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(recipe, "docs/agents.md", "exec"), namespace)
    (video,) = (tmp_path / "videos").glob("*.mp4")
    assert video.stat().st_size > 10_000
