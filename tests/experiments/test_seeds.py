"""Across training seeds: per-run gains and their mean where the answer is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from vgs.analysis.seeds import load_seeds, mean_gain, seeds_report, seeds_table
from vgs.analysis.stats import TOTAL_GAIN, time_arrays, total_gain_pct
from vgs.errors import ConfigError


def _table(policy: str, times: np.ndarray, run: str, root_seed: int = 7) -> pd.DataFrame:
    n = times.size
    return pd.DataFrame({
        "index": np.arange(n), "policy": policy, "condition": "nominal", "root_seed": root_seed,
        "seed": np.arange(n) + 100, "peg_mass_kg": 0.55, "peg_length_mm": 100.0,
        "grasp_success": True, "assembly_success": True, "failure_reason": "",
        "assembly_time_s": times, "adjustments": 3, "retries": 0,
        "grasp_offset_mm": 10.0 if policy == "vgs" else 30.0,
        "train_run": run,
    })


def _folder(root: Path, run: str, speed_up: float, root_seed: int = 7,
            policies: tuple[str, ...] = ("baseline", "vgs")) -> Path:
    """A results folder whose VGS is ``speed_up`` (fraction) faster on the same scenes."""
    rng = np.random.default_rng([int(run[1:]), abs(int(1000 * speed_up))])
    base = rng.uniform(100, 160, 300)
    times = {"baseline": base, "vgs": (1 - speed_up) * base + rng.normal(0, 1, 300),
             "center": 0.5 * base}
    folder = root / run
    for policy in policies:
        dest = folder / "eval" / policy / "nominal"
        dest.mkdir(parents=True)
        _table(policy, times[policy], run, root_seed).to_parquet(dest / "episodes.parquet")
    return folder


def test_two_runs_give_their_gains_and_the_mean(tmp_path: Path) -> None:
    folders = [_folder(tmp_path, "s0", 0.10, policies=("baseline", "vgs", "center")),
               _folder(tmp_path, "s1", 0.20)]
    table = seeds_table(load_seeds(folders)).set_index("train_run")
    assert table.loc["s0", "gain_pct"] == pytest.approx(10.0, abs=0.5)
    assert table.loc["s1", "gain_pct"] == pytest.approx(20.0, abs=0.5)
    mean = table.loc["mean"]
    assert mean["gain_pct"] == pytest.approx(15.0, abs=0.5)
    # The outer bootstrap level draws {s0, s0}, {s0, s1} or {s1, s1}: the interval spans the
    # two runs' gains, far wider than either run's own interval.
    assert 9.0 < mean["gain_ci_low"] < 12.0 and 18.0 < mean["gain_ci_high"] < 21.0
    assert table.loc["s0", "gain_ci_high"] - table.loc["s0", "gain_ci_low"] < 2.0
    assert mean["seeds"] == 2 and mean["seeds_with_positive_gain"] == 2
    assert mean["gain_sd_between_seeds"] == pytest.approx(np.std([10, 20], ddof=1), abs=0.5)
    assert mean["successes_baseline"] == 600
    # Every test assembled: the gain in total time is the gain on the mean (the paper's case).
    assert mean["total_gain_pct"] == pytest.approx(mean["gain_pct"], abs=0.3)
    assert mean["seeds_with_positive_total_gain"] == 2


def test_mean_gain_of_identical_runs_is_the_run_gain() -> None:
    rng = np.random.default_rng(3)
    base = rng.uniform(100, 160, 200)
    pair = (_table("baseline", base, "s0"), _table("vgs", 0.9 * base, "s0"))
    value, low, high = mean_gain([pair, pair, pair])
    assert value == pytest.approx(10.0) and low == pytest.approx(10.0, abs=1e-6)
    assert high == pytest.approx(10.0, abs=1e-6)


def test_shared_scenes_do_not_average_out_over_runs() -> None:
    """Four copies of one run on the same scenes: the crossed bootstrap keeps the scenes'
    spread (the interval of one run); a nested one would shrink it by about sqrt(4)."""
    rng = np.random.default_rng(5)
    base = rng.uniform(100, 160, 300)
    vgs = 0.85 * base + rng.normal(0.0, 20.0, 300)
    pair = (_table("baseline", base, "s0"), _table("vgs", vgs, "s0"))
    _, low1, high1 = mean_gain([pair])
    value, low4, high4 = mean_gain([pair] * 4)
    assert value == pytest.approx(mean_gain([pair])[0])
    assert (high4 - low4) == pytest.approx(high1 - low1, rel=0.2)
    assert (high4 - low4) > 0.8 * (high1 - low1)


def test_total_time_gain_pays_for_failures() -> None:
    """Baseline: half its tests assemble in 100 s, the other half fail after 200 s; VGS
    assembles every test in 90 s. Mean of the successes: +10 %; total time (the paper's
    measure): (150 - 90) / 150 = +40 %. A missed grasp (time NaN) costs none."""
    n = 200
    base = _table("baseline", np.where(np.arange(n) % 2 == 0, 100.0, 200.0), "s0")
    base["assembly_success"] = np.arange(n) % 2 == 0
    vgs = _table("vgs", np.full(n, 90.0), "s0")
    assert mean_gain([(base, vgs)])[0] == pytest.approx(10.0)
    value, low, high = mean_gain([(base, vgs)], measure=TOTAL_GAIN)
    assert value == pytest.approx(40.0)
    assert low < 40.0 < high and high - low < 10.0  # which tests failed varies per draw
    missed = base.copy()
    missed.loc[1, ["assembly_time_s", "grasp_success"]] = [np.nan, False]
    expected = 100 * (1 - 90 * n / (150 * n - 200))
    assert total_gain_pct(*time_arrays(missed), *time_arrays(vgs)) == pytest.approx(expected)


def test_tables_on_other_episodes_are_refused() -> None:
    base = np.full(10, 120.0)
    pair = (_table("baseline", base, "s0"), _table("vgs", 0.9 * base, "s0"))
    other = (_table("baseline", base[:8], "s1"), _table("vgs", 0.9 * base[:8], "s1"))
    with pytest.raises(ConfigError):
        mean_gain([pair, other])


def test_one_run_twice_is_refused(tmp_path: Path) -> None:
    a = _folder(tmp_path / "a", "s0", 0.1)
    b = _folder(tmp_path / "b", "s0", 0.1)
    with pytest.raises(ConfigError, match="s0 on the nominal condition is in both"):
        load_seeds([a, b])


def test_one_run_on_other_conditions_in_another_folder(tmp_path: Path) -> None:
    a = _folder(tmp_path / "a", "s0", 0.1)
    b = _folder(tmp_path / "b", "s0", 0.2)
    for path in (b / "eval").rglob("episodes.parquet"):
        df = pd.read_parquet(path).assign(condition="mass")
        dest = path.parent.parent / "mass"
        dest.mkdir()
        df.to_parquet(dest / "episodes.parquet")
        path.unlink()
    table = seeds_table(load_seeds([a, b])).set_index(["condition", "train_run"])
    assert table.loc[("nominal", "s0"), "gain_pct"] == pytest.approx(10.0, abs=0.5)
    assert table.loc[("mass", "s0"), "gain_pct"] == pytest.approx(20.0, abs=0.5)


def test_other_test_scenes_are_refused(tmp_path: Path) -> None:
    folders = [_folder(tmp_path, "s0", 0.1), _folder(tmp_path, "s1", 0.1, root_seed=8)]
    with pytest.raises(ConfigError, match="different test scenes"):
        load_seeds(folders)


def test_a_folder_without_learned_policies_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no baseline or VGS"):
        load_seeds([_folder(tmp_path, "s0", 0.1, policies=("center",))])
    with pytest.raises(ConfigError, match="no evaluation results"):
        load_seeds([tmp_path / "nothing"])


def test_report_files(tmp_path: Path) -> None:
    folders = [_folder(tmp_path, "s0", -0.05), _folder(tmp_path, "s1", 0.05)]
    path = seeds_report(folders, tmp_path / "out")
    text = path.read_text()
    assert "1 of 2 training runs give VGS the shorter mean time" in text
    assert "includes zero" in text and "+13.83 %" in text
    assert "two training runs only" in text  # an interval over two runs says little
    assert (tmp_path / "out" / "seeds.png").stat().st_size > 10_000
    three = seeds_report([*folders, _folder(tmp_path, "s2", 0.10)], tmp_path / "out3")
    assert "two training runs only" not in three.read_text()
    assert "three training runs only" in three.read_text()
    summary = text.split("## Summary")[1].split("## ")[0].strip().splitlines()
    assert summary[0].startswith("| condition | assembled of 300, baseline / VGS (s0; s1) |")
    assert len(summary) == 3 and summary[2].startswith("| Nominal peg | 300 / 300; 300 / 300 |")
    per_run = [float(g.rstrip(" %")) for g in summary[2].split(" | ")[2].split("; ")]
    assert per_run == pytest.approx([-5.0, 5.0], abs=0.3)
    assert summary[2].endswith("| +13.83 % |")
    csv = pd.read_csv(tmp_path / "out" / "seeds.csv")
    assert list(csv["train_run"]) == ["s0", "s1", "mean"]
