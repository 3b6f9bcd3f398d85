"""The analysis script of scripts/ runs at a tiny size, so that it cannot rot."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VGS = str(Path(sys.executable).with_name("vgs"))


def test_fit_input_modes_runs_on_a_smoke_training_run(tmp_path: Path) -> None:
    """scripts/fit_input_modes.py fits both network inputs to a run's transitions and prints
    one line per input (a 4-episode smoke run, 2 SGD steps, 2 held-out scenes)."""
    run = tmp_path / "run"
    train = subprocess.run([VGS, "train", "--mode", "vgs", "--profile", "smoke", "--out",
                            str(run), "--no-progress"], capture_output=True, text=True,
                           timeout=600)
    assert train.returncode == 0, train.stderr
    fit = subprocess.run([sys.executable, str(ROOT / "scripts" / "fit_input_modes.py"), str(run),
                          "--profile", "smoke", "--transitions", "4", "--steps", "2",
                          "--test-seeds", "2"], capture_output=True, text=True, timeout=600)
    assert fit.returncode == 0, fit.stderr
    lines = [line for line in fit.stdout.splitlines() if line.startswith("rotate=")]
    assert [line.split()[0] for line in lines] == ["rotate=input", "rotate=none"]
    assert all("interquartile range" in line for line in lines)
