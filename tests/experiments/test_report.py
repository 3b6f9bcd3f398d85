"""The report: statistics where the answer is known, and a build from a stored result set."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from vgs.analysis.report import PAPER, build_report, efficiency_gain
from vgs.config import profile, to_dict
from vgs.errors import ConfigError

DATA = Path(__file__).resolve().parents[1] / "data" / "report_small"


def _table(policy: str, times: np.ndarray, condition: str = "nominal",
           success: np.ndarray | None = None) -> pd.DataFrame:
    n = times.size
    ok = np.ones(n, bool) if success is None else success
    return pd.DataFrame({
        "index": np.arange(n), "policy": policy, "condition": condition, "root_seed": 0,
        "seed": np.arange(n) + 100, "peg_mass_kg": 0.55, "peg_length_mm": 100.0,
        "grasp_success": True, "assembly_success": ok,
        "failure_reason": np.where(ok, "", "timeout:align"),
        "assembly_time_s": np.where(ok, times, np.nan), "adjustments": 3, "retries": 0,
        "grasp_offset_mm": 10.0 if policy == "vgs" else 30.0,
    })


def test_gain_of_a_known_speed_up() -> None:
    rng = np.random.default_rng(0)
    base = rng.uniform(100, 160, 400)
    vgs = 0.86 * base + rng.normal(0, 2, 400)  # 14 % faster on the same scenes
    gain = efficiency_gain(_table("baseline", base), _table("vgs", vgs))
    assert gain.paired
    assert gain.value == pytest.approx(14.0, abs=0.5)
    assert gain.low < gain.value < gain.high and gain.low > 12.0 and gain.high < 16.0


def test_no_difference_gives_an_interval_around_zero() -> None:
    rng = np.random.default_rng(1)
    a, b = rng.uniform(100, 160, 300), rng.uniform(100, 160, 300)
    gain = efficiency_gain(_table("baseline", a), _table("vgs", b))
    assert gain.low < 0 < gain.high


def test_failures_are_left_out_of_the_times() -> None:
    t = np.full(10, 100.0)
    ok = np.array([True] * 5 + [False] * 5)
    slow = np.where(ok, 50.0, 1e6)  # huge times of failed episodes must not count
    gain = efficiency_gain(_table("baseline", t), _table("vgs", slow, success=ok))
    assert gain.value == pytest.approx(50.0)


def test_time_per_assembled_peg_counts_failed_attempts() -> None:
    from vgs.analysis.stats import summarize

    df = _table("vgs", np.array([40.0, 60.0, 0.0, 0.0]),
                success=np.array([True, True, False, False]))
    df.loc[2, "assembly_time_s"] = 100.0  # an attempt given up after 100 s
    df.loc[3, "grasp_success"] = False  # a missed grasp: no assembly time
    s = summarize(df)
    assert s["time_mean_s"] == pytest.approx(50.0)  # successful assemblies only
    assert s["time_per_assembled_s"] == pytest.approx((40.0 + 60.0 + 100.0) / 2)
    # The paper's measure, the total time of all tests: failed attempts until given up.
    assert s["time_all_h"] == pytest.approx((40.0 + 60.0 + 100.0) / 3600.0)
    assert s["time_total_h"] == pytest.approx((40.0 + 60.0) / 3600.0)  # successes only
    assert summarize(df.assign(assembly_success=False))["time_per_assembled_s"] is None


def test_report_says_when_vgs_is_slower(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    base = rng.uniform(100, 160, 200)
    for policy, times in (("baseline", base), ("vgs", 1.2 * base)):
        folder = tmp_path / "eval" / policy / "nominal"
        folder.mkdir(parents=True)
        _table(policy, times).to_parquet(folder / "episodes.parquet")
    text = build_report(tmp_path).read_text()
    assert "VGS was SLOWER than the baseline" in text
    assert "-20.00 %" in text


def test_report_builds_from_a_stored_result_set(tmp_path: Path) -> None:
    shutil.copytree(DATA, tmp_path / "run")
    md = build_report(tmp_path / "run")
    text = md.read_text()
    for heading in ("## Headline", "## Nominal peg (paper Fig. 8)", "## Mass +-15 % (paper Fig. 9)",
                    "## Length 85-115 %, mass following (paper Fig. 10)",
                    "## Where the policies grasp"):
        assert heading in text
    # the paper's numbers stand beside ours
    for value in ("38.46", "33.14", "+13.83", "+12.13", "+10.92", "5.1756", "3.0133", "6.2242",
                  "3.8508", "157.0", "135.0", "106.0"):
        assert value in text, value
    assert PAPER["nominal"]["gain"] == 13.83
    for image in re.findall(r"\]\((figures/[^)]+\.png)\)", text):
        assert (tmp_path / "run" / image).stat().st_size > 5_000
    html = (tmp_path / "run" / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 4
    assert 'src="figures' not in html  # self-contained
    results = pd.read_csv(tmp_path / "run" / "results.csv")
    assert set(results["condition"]) == {"nominal", "mass", "length"}
    assert set(results["policy"]) == {"baseline", "vgs", "center"}


def test_report_without_results_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no evaluation results"):
        build_report(tmp_path)


def test_too_few_successes_give_no_interval() -> None:
    t = np.linspace(100, 150, 10)
    ok = np.zeros(10, bool)
    ok[:2] = True
    gain = efficiency_gain(_table("baseline", t, success=ok), _table("vgs", 0.5 * t))
    assert np.isnan(gain.low) and "too few successes" in gain.text()


def test_report_states_each_runs_own_wall_time(tmp_path: Path) -> None:
    """The runs' tables count what reproduce.json cannot: a run trained outside ``vgs
    reproduce`` (scripts/paper_light.sh's baseline), interrupted or moved between machines."""
    import json

    from vgs.runfolder.trainfolder import CSV_COLUMNS

    run = tmp_path / "run"
    shutil.copytree(DATA, run)
    (run / "reproduce.json").write_text(json.dumps(
        {"profile": "paper-light", "config": to_dict(profile("paper-light")),
         "stage_wall_s": {"train": 1800.0, "evaluate": 5400.0}}))
    for mode, wall in (("baseline", 0.6), ("vgs", 1.8)):
        rows = [{c: "" for c in CSV_COLUMNS} | {
            "episode": i, "mode": mode, "seed": i, "epsilon": 0.5, "explored": "True",
            "rotation": 0, "row": 1, "col": 1, "grasp_success": "True",
            "grasp_offset_mm": 5.0, "assembly_success": "False", "adjustments": 0,
            "r_grasp": 0.3, "r_assembly": 0.0, "reward": 0.3, "loss": 0.1, "delta_q": 0.1,
            "wall_s": wall} for i in range(3000)]
        folder = run / "train" / f"{mode}_s0"
        folder.mkdir(parents=True)
        (folder / "run.json").write_text(json.dumps(
            {"mode": mode, "config": to_dict(profile("paper-light"))}))
        pd.DataFrame(rows, columns=list(CSV_COLUMNS)).to_csv(folder / "episodes.csv",
                                                             index=False)
    text = build_report(run).read_text()
    assert "train 30.0 min, evaluate 90.0 min (2.00 h in all)" in text
    assert "baseline_s0 30.0 min, vgs_s0 90.0 min" in text
    # The test episodes' own wall time, from the tables' wall_s (DATA's sums: 76.073 s,
    # 58.056 s and 75.808 s), in the unit that fits (it read "0.02 h" each).
    assert "baseline 76 s, center 58 s, vgs 76 s (3.5 min in all)" in text
