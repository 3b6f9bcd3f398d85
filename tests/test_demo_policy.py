"""Watching a policy (issue 42, items 1 and 7): ``vgs demo --policy`` with a published run's
network writes a playable video with its Q heat map beside the episode; ``vgs evaluate
--videos N`` renders its first test episodes afterwards, run again by their seeds; an .mp4
without the video writer is refused before the episode."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vgs.render import gl_available

ROOT = Path(__file__).resolve().parents[1]
PUBLISHED = ROOT / "docs" / "results" / "paper_light_s0" / "vgs"
GL, GL_REASON = gl_available()
needs_gl = pytest.mark.skipif(not GL, reason=f"no OpenGL for MuJoCo's renderer: {GL_REASON}")
SMALL = ["--profile", "smoke", "--set", "cell.camera.size=64", "--set",
         "cell.camera.pixel_size=0.007"]


def vgs(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "vgs.cli", *args], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


def frames(path: Path) -> list[np.ndarray]:
    imageio = pytest.importorskip("imageio.v2")
    with imageio.get_reader(path) as reader:
        return [np.asarray(f) for f in reader]


@needs_gl
@pytest.mark.slow
def test_demo_of_a_published_policy_writes_a_video_with_its_heat_map(tmp_path: Path) -> None:
    proc = vgs("demo", "--policy", str(PUBLISHED), "--video", "demo.mp4", "--out", ".",
               "--video-size", "320x240", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "success" in proc.stdout and (tmp_path / "demo.png").stat().st_size > 50_000
    video = frames(tmp_path / "demo.mp4")
    assert len(video) > 50 and video[0].shape == (240, 320 + 240, 3)
    side = video[0][:, 320:].astype(float)
    assert side.std() > 20  # the heat map panel, not a blank one
    hot = (side[..., 0] > 150) & (side[..., 2] < 100)  # the inferno map's warm pixels
    assert hot.sum() > 100


@needs_gl
@pytest.mark.slow
def test_evaluate_videos_renders_the_first_episodes_afterwards(tmp_path: Path) -> None:
    proc = vgs("evaluate", "--policy", "random", "--episodes", "2", "--videos", "1",
               "--workers", "1", "--no-progress", "--out", "ev", *SMALL, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "ended otherwise" not in proc.stderr  # the second run is the same episode
    (video,) = (tmp_path / "ev" / "videos").iterdir()
    assert video.name == "episode_0000.mp4" and len(frames(video)) > 50


def test_mp4_without_the_writer_is_refused_before_the_episode(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['imageio'] = None; sys.modules['imageio_ffmpeg'] = None; "
            "from vgs.cli import main; sys.exit(main(sys.argv[1:]))")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, "demo", "--video", "x.mp4", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "vgs[video]" in proc.stderr
    assert "phase" not in proc.stdout and time.perf_counter() - t0 < 20
