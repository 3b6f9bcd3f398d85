"""Subprocess smoke runs of ``vgs train`` and ``vgs heatmap``, and their input errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

SMALL = ["--profile", "smoke", "--set", "cell.camera.size=64", "--set",
         "cell.camera.pixel_size=0.007"]


def vgs(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vgs.cli", *args], capture_output=True,
                          text=True, timeout=900)


@pytest.mark.slow
def test_train_then_heatmap(tmp_path: Path) -> None:
    run = tmp_path / "run"
    result = vgs("train", "--mode", "baseline", "--episodes", "2", "--out", str(run),
                 "--no-progress", *SMALL)
    assert result.returncode == 0, result.stderr
    assert (run / "checkpoint.pt").exists() and (run / "run.json").exists()
    lines = (run / "episodes.csv").read_text().strip().splitlines()
    assert len(lines) == 3 and lines[0].startswith("episode,mode,seed")
    fig = tmp_path / "heat.png"
    result = vgs("heatmap", str(run), "--out", str(fig), "--scenes", "1")  # the run's config
    assert result.returncode == 0, result.stderr
    assert fig.stat().st_size > 10_000
    curves = tmp_path / "curves.png"
    result = vgs("curves", str(run), "--out", str(curves), "--window", "2", "--json")
    assert result.returncode == 0, result.stderr
    assert "last_window" in result.stdout and curves.stat().st_size > 10_000


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["train", "--mode", "vgs", "--out", "x", "--set", "agent.momentum=2", "--profile",
          "smoke"], "agent.momentum"),
        (["train", "--mode", "vgs", "--out", "x", "--episodes", "0", "--profile", "smoke"],
         "--episodes: must lie in [1, 1000000]"),
        (["train", "--mode", "vgs", "--out", "x", "--backbone", "resnet", "--profile", "smoke"],
         "network.backbone"),
        (["heatmap", "no/such/run", "--out", "x.png"], "run_dir"),
        (["curves", "no/such/run", "--out", "x.png"], "run_dir"),
        # a run folder's commands read the run's own configuration: no profile, no overrides
        (["heatmap", "no/such/run", "--out", "x.png", "--profile", "smoke"], "heatmap"),
        (["curves", "no/such/run", "--out", "x.png", "--set", "seed=1"], "curves"),
    ],
)
def test_bad_training_input_is_one_line_exit_2(args: list[str], field: str) -> None:
    result = vgs(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "Traceback" not in result.stderr
