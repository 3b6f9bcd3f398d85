"""Test session set-up: MuJoCo renders headless (``MUJOCO_GL=egl``) where no display is set.

MuJoCo reads ``MUJOCO_GL`` when it is first imported, so this runs before the test modules
import it. Where EGL is missing too, the rendering tests skip with the reason.

The fixture :func:`quick_reproduction` runs the README's main job once per session, shrunk to
seconds; the tests of the command and of the tables it writes share it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

if "MUJOCO_GL" not in os.environ and not (os.environ.get("DISPLAY")
                                          or os.environ.get("WAYLAND_DISPLAY")):
    os.environ["MUJOCO_GL"] = "egl"


VGS = str(Path(sys.executable).with_name("vgs"))
QUICK_ARGS = ("reproduce", "--profile", "quick", "--workers", "2", "--no-progress",
              "--set", "train.episodes=2", "--set", "agent.random_episodes=1",
              "--set", "train.checkpoint_every=1", "--set", "eval.episodes=1",
              "--set", "reproduce.conditions=('nominal', 'mass')",
              "--set", "reproduce.sweep_offsets=1", "--set", "reproduce.sweep_trials=1")


@dataclass(frozen=True)
class Reproduction:
    """A finished ``vgs reproduce`` (:data:`QUICK_ARGS` plus ``--out``) and its process."""

    out: Path
    args: tuple[str, ...]
    proc: subprocess.CompletedProcess[str]


@pytest.fixture(scope="session")
def quick_reproduction(tmp_path_factory: pytest.TempPathFactory) -> Reproduction:
    """``vgs reproduce --profile quick`` at reduced size (2 training episodes per mode, one test
    episode per policy and condition, a one-trial sweep), run once per session: training runs,
    evaluations, merged tables, sweep and report."""
    root = tmp_path_factory.mktemp("quick_reproduction")
    out = root / "repro"
    args = (*QUICK_ARGS, "--out", str(out))
    proc = subprocess.run([VGS, *args], cwd=root, capture_output=True, text=True, timeout=600)
    return Reproduction(out, args, proc)
