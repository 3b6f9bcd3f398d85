"""Where on the peg a test grasp lay (``vgs grasp-sites``): a pixel placed at a known point of
the peg of a scene comes back as that point, and the table counts what assembled."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from vgs.analysis.graspsites import folder_config, grasp_sites, sites_table
from vgs.assembly.episode import EpisodeRunner
from vgs.config import profile
from vgs.errors import ConfigError


def test_a_pixel_at_a_known_point_of_the_peg_comes_back_as_that_point() -> None:
    cfg = profile("smoke")
    runner = EpisodeRunner(cfg)
    seed, peg = 11, cfg.cell.peg
    hm = runner.observe(seed, peg)
    cell, _ = runner.cell(peg)
    p_world_peg, R_world_peg = cell.peg_pose()
    a = R_world_peg[:2, 2] / np.linalg.norm(R_world_peg[:2, 2])
    n = np.array([-a[1], a[0]])  # across the axis, in the table plane
    rows = []
    for along, across in ((20e-3, 8e-3), (-30e-3, -12e-3), (0.0, 0.0)):
        x, y = p_world_peg[:2] + along * a + across * n
        rows.append(hm.world_to_pixel(x, y))
    rows.append((-1, -1))  # a decision without a pixel: the centre heuristic
    df = pd.DataFrame({"policy": "random", "condition": "nominal", "seed": seed,
                       "peg_mass_kg": peg.mass, "peg_length_mm": peg.length * 1000,
                       "row": [r for r, _ in rows], "col": [c for _, c in rows],
                       "grasp_offset_mm": [20.0, -30.0, 0.0, 0.0],
                       "assembly_success": [True, False, True, True]})
    sites = grasp_sites(df, cfg, progress=False)
    # two spawned processes, the grasps shuffled between them: the same table
    pd.testing.assert_frame_equal(grasp_sites(df, cfg, progress=False, workers=2), sites)
    half_diagonal_mm = 1000 * hm.pixel_size / np.sqrt(2)  # a pixel's centre vs the point
    assert np.allclose(sites["along_mm"][:3], [20.0, -30.0, 0.0], atol=half_diagonal_mm)
    assert np.allclose(sites["across_mm"][:3], [8.0, 12.0, 0.0], atol=half_diagonal_mm)
    assert np.isnan(sites["along_mm"][3]) and np.isnan(sites["across_mm"][3])


def test_the_table_counts_assembled_of_tested_per_bin() -> None:
    sites = pd.DataFrame({
        "policy": "baseline", "condition": "nominal",
        "along_mm": [5.0, -6.0, 20.0, 42.0, -43.0, 50.0],
        "across_mm": [1.0, 12.0, 13.0, 2.0, 14.0, 6.0],
        "grasp_offset_mm": [5.0, -6.0, 20.0, 42.0, -43.0, 50.0],
        "assembly_success": [True, True, False, True, False, True],
        "peg_turn_deg": [0.5, 1.5, 2.5, 1.0, 4.0, np.nan],
    })
    text = sites_table(sites)
    assert "**baseline, nominal**" in text and "median across the axis 9.0 mm" in text
    lines = {line.split(" | ")[0]: line for line in text.splitlines() if line.startswith("| ")}
    assert lines["| 0-26"] == ("| 0-26 | 1/1, 0.5 deg | - | 1/2, 2.0 deg | 2/3, 1.5 deg |")
    assert lines["| 40-45"] == "| 40-45 | 1/1, 1.0 deg | - | 0/1, 4.0 deg | 1/2, 2.5 deg |"
    assert lines["| 45+"] == "| 45+ | - | 1/1 | - | 1/1 |"


def test_a_folder_without_reproduce_json_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no reproduce.json"):
        folder_config(tmp_path)
