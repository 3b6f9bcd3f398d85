"""The joint fit of a shifted-mass sweep (``vgs com-fit``): on tables whose times are made to
follow one distance, it names that distance."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from vgs.analysis.comfit import analyse, markdown

OFFSETS = (-35.0, -26.25, -17.5, -8.75, 0.0, 8.75, 17.5, 26.25, 35.0)


def _sweep(shift: float, through: str, seed: int = 0) -> pd.DataFrame:
    """A synthetic sweep: the heavy end on a random side per scene; time = 30 s + 0.2 s per mm
    of the chosen distance + noise; alignment a third of it."""
    rng = np.random.default_rng(seed)
    rows = []
    for trial in range(40):
        side = rng.choice([-1.0, 1.0])  # the heavy end's direction relative to the offsets
        noise = rng.normal(0, 0.5)
        for offset in OFFSETS:
            along = side * offset  # signed along the heavy end
            d = abs(along - shift) if through == "com" else abs(along)
            t = 30.0 + 0.2 * d + noise
            rows.append({"offset_mm": offset, "trial": trial, "assembly_success": True,
                         "assembly_time_s": t, "time_align_s": t / 3,
                         "grasp_offset_mm": along, "grasp_offset_com_mm": along - shift,
                         "peg_com_shift_mm": shift})
    return pd.DataFrame(rows)


@pytest.mark.parametrize("through", ["com", "middle"])
def test_the_fit_names_the_distance_the_times_follow(through: str) -> None:
    doc = analyse(_sweep(20.0, through), _sweep(0.0, through), resamples=200)
    joint = doc["fits"]["assembly"]["shifted_joint"]
    com, mid = joint["per_mm_from_com_s"]["value"], joint["per_mm_from_middle_s"]["value"]
    if through == "com":
        assert com == pytest.approx(0.2, abs=0.02) and abs(mid) < 0.02
        assert "centre of mass (the mass" in doc["verdict"]
    else:
        assert mid == pytest.approx(0.2, abs=0.02) and abs(com) < 0.02
        assert "from the middle (the peg's geometry)" in doc["verdict"]
    assert doc["fits"]["assembly"]["twin"]["per_mm_from_middle_s"]["value"] == \
        pytest.approx(0.2, abs=0.02)
    assert len(doc["paired"]) == len(OFFSETS)
    assert "| assembly | shifted |" in markdown(doc)


def test_the_command_reads_two_sweep_folders(tmp_path: Path) -> None:
    for name, shift in (("com20", 20.0), ("twin", 0.0)):
        (tmp_path / name).mkdir()
        _sweep(shift, "com").to_csv(tmp_path / name / "sweep.csv", index=False)
    proc = subprocess.run([sys.executable, "-m", "vgs.cli", "com-fit", str(tmp_path / "com20"),
                           "--twin", str(tmp_path / "twin"), "--out", str(tmp_path / "fit")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "fit" / "com_fit.json").exists()
    (tmp_path / "old").mkdir()
    pd.DataFrame({"offset_mm": [0.0]}).to_csv(tmp_path / "old" / "sweep.csv", index=False)
    bad = subprocess.run([sys.executable, "-m", "vgs.cli", "com-fit", str(tmp_path / "old")],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
