"""What the gain is made of, the regret against the centre and the field's statistics across
runs (issue 52), on synthetic tables whose answer is known; the figures' and texts' honesty
(issue 54 item 5)."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from vgs.analysis.makeup import check_center, condition_pairs, gain_makeup
from vgs.analysis.stats import (
    ACROSS_SITES,
    ALONG_SITES,
    along_sites,
    both_within,
    efficiency_gain,
    failed_share_pct,
    improvement_probability,
    iqm,
    iqm_interval,
    phase_gap,
    regret,
    site_gap,
    win_matrix,
)
from vgs.errors import ConfigError

DATA = Path(__file__).resolve().parents[1] / "data" / "report_small"
PHASES = ("transport", "approach", "search", "slide", "align", "insert")


def _table(policy: str, phases: np.ndarray, offset: np.ndarray | float = 10.0,
           ok: np.ndarray | None = None, across: np.ndarray | None = None,
           retries: np.ndarray | int = 0, run: str = "s0") -> pd.DataFrame:
    """A table of ``len(phases)`` tests; ``phases``: tests x 6 phase times [s]."""
    n = len(phases)
    ok = np.ones(n, bool) if ok is None else ok
    df = pd.DataFrame({"index": np.arange(n), "policy": policy, "condition": "nominal",
                       "root_seed": 7, "seed": np.arange(n) + 100, "grasp_success": True,
                       "grasp_offset_mm": offset, "assembly_success": ok,
                       "failure_reason": np.where(ok, "", "timeout:search"),
                       "assembly_time_s": phases.sum(axis=1), "retries": retries,
                       "train_run": run})
    for i, p in enumerate(PHASES):
        df[f"time_{p}_s"] = phases[:, i]
    if across is not None:
        df["across_mm"] = across
    return df


def _phases(total: np.ndarray, search_share: float = 0.5) -> np.ndarray:
    """Phase times that sum to ``total``: the search ``search_share``, the rest spread."""
    total = np.asarray(total, float)
    rest = (1 - search_share) * total / 5
    return np.stack([rest, rest, search_share * total, rest, rest, rest], axis=1)


def test_the_phase_rows_sum_to_the_gap_and_carry_what_was_built_in() -> None:
    rng = np.random.default_rng(0)
    base = _phases(rng.uniform(40, 80, 200))
    vgs = base.copy()
    vgs[:, 2] -= 6.0  # VGS searches 6 s less, aligns 2 s less, the rest the same
    vgs[:, 4] -= 2.0
    ok = np.ones(200, bool)
    ok[:20] = False  # failed tests are not among the successes' means
    gap = phase_gap(_table("baseline", base, ok=ok), _table("vgs", vgs, ok=ok))
    assert gap["gap"] == pytest.approx(8.0)
    assert gap["search"] == pytest.approx(6.0) and gap["align"] == pytest.approx(2.0)
    assert sum(v for k, v in gap.items() if k != "gap") == pytest.approx(gap["gap"], abs=1e-9)
    assert gap["other"] == pytest.approx(0.0, abs=1e-9)


def test_the_site_split_is_exact_and_known() -> None:
    """Baseline: half its successes within +-26 mm at 40 s, half beyond 35 mm at 60 s (mean
    50 s); VGS: all within at 40 s (mean 40 s). M = 45 s; within: mix (0.5 - 1)(40 - 45) =
    +2.5 s, rate 0; beyond: mix 0.5 (60 - 45) = +7.5 s; 26-35 mm: nothing. Sum: the 10 s gap."""
    n = 100
    base = _table("baseline", _phases(np.r_[np.full(50, 40.0), np.full(50, 60.0)]),
                  offset=np.r_[np.full(50, 5.0), np.full(50, -40.0)])
    vgs = _table("vgs", _phases(np.full(n, 40.0)), offset=np.full(n, 3.0))
    parts = {p.site: p for p in site_gap(along_sites(base["grasp_offset_mm"]), base,
                                         along_sites(vgs["grasp_offset_mm"]), vgs,
                                         ALONG_SITES)}
    assert parts["within +-26 mm"].mix_s == pytest.approx(2.5)
    assert parts["within +-26 mm"].rate_s == pytest.approx(0.0)
    assert parts["beyond 35 mm"].part_s == pytest.approx(7.5)
    assert parts["26-35 mm"].part_s == 0.0 and math.isnan(parts["26-35 mm"].mean_vgs_s)
    assert sum(p.part_s for p in parts.values()) == pytest.approx(10.0)
    assert list(along_sites([25.9, -26.0, 34.9, 35.0, np.nan])) == [
        "within +-26 mm", "26-35 mm", "26-35 mm", "beyond 35 mm", "no grasp"]


def test_a_rate_difference_lands_in_the_rate_term() -> None:
    rng = np.random.default_rng(1)
    off = rng.uniform(-50, 50, 400)
    t = 40 + 0.3 * np.abs(off)
    base = _table("baseline", _phases(t), offset=off)
    vgs = _table("vgs", _phases(t - 3.0), offset=off)  # same sites, 3 s faster everywhere
    parts = site_gap(along_sites(off), base, along_sites(off), vgs, ALONG_SITES)
    assert all(p.mix_s == pytest.approx(0.0, abs=1e-9) for p in parts)
    assert sum(p.rate_s for p in parts) == pytest.approx(3.0)


def test_failed_attempts_share_and_the_gain_within_26_mm() -> None:
    # Baseline: 10 failed attempts of 100 s and 90 successes of 50 s; VGS: all 100 at 45 s.
    tb = np.r_[np.full(10, 100.0), np.full(90, 50.0)]
    ob = np.r_[np.zeros(10, bool), np.ones(90, bool)]
    tv, ov = np.full(100, 45.0), np.ones(100, bool)
    # S_b = 1000 + 4500 = 5500, S_v = 4500: the whole 1000 s gain in total time is the failed
    # attempts' (F_b - F_v = 1000 - 0); VGS's successes sum as much as the baseline's.
    assert failed_share_pct(tb, ob, tv, ov) == pytest.approx(100.0)
    tv2 = np.full(100, 44.0)  # now VGS's successes also save 100 s: 1000 of 1100
    assert failed_share_pct(tb, ob, tv2, ov) == pytest.approx(100.0 * 1000 / 1100)
    # Within +-26 mm: the first 60 scenes both policies grasp near the centre, VGS 10 % faster
    # there; elsewhere VGS is 40 % faster. The restricted gain sees only the 10 %.
    off_b = np.r_[np.full(60, 10.0), np.full(40, 40.0)]
    t_b = np.full(100, 50.0)
    t_v = np.r_[np.full(60, 45.0), np.full(40, 30.0)]
    base = _table("baseline", _phases(t_b), offset=off_b)
    vgs = _table("vgs", _phases(t_v), offset=5.0)
    wb, wv = both_within(base, vgs)
    gain = efficiency_gain(wb, wv)
    assert gain.value == pytest.approx(10.0) and gain.low == pytest.approx(10.0)
    assert efficiency_gain(base, vgs).value == pytest.approx(100 * (50 - 39) / 50)


def _regret_case(with_across: bool) -> tuple[pd.DataFrame, pd.DataFrame]:
    """40 scenes, the centre 40 s on each. VGS: scenes 0-9 re-searched (+10 s), 10-19 on the
    flank, 8 mm beside the axis (+4 s), 20-39 on the axis (+1 s); one more scene VGS failed.
    Regret (100 + 40 + 20) / 40 = 4 s: re-searches 2.5 s, flank 1 s, along the axis 0.5 s."""
    center = _table("center", _phases(np.full(41, 40.0)), offset=0.5)
    t = np.r_[np.full(10, 50.0), np.full(10, 44.0), np.full(20, 41.0), 120.0]
    ok = np.r_[np.ones(40, bool), False]
    across = np.r_[np.full(10, 8.0), np.full(10, -8.0), np.full(20, 1.0), 1.0]
    vgs = _table("vgs", _phases(t), ok=ok, across=across if with_across else None,
                 retries=np.r_[np.ones(10, int), np.zeros(31, int)])
    return center, vgs


def test_the_regret_split_is_known() -> None:
    center, vgs = _regret_case(with_across=True)
    r = regret(center, vgs)
    assert r.n == 40 and r.mean_s == pytest.approx(4.0)
    assert r.parts["re-searches"][0] == pytest.approx(2.5) and r.parts["re-searches"][3] == 10
    assert r.parts["flank pixels"][0] == pytest.approx(1.0)  # signed across_mm: its magnitude
    assert r.parts["along-axis offset"][0] == pytest.approx(0.5)
    assert sum(p[0] for p in r.parts.values()) == pytest.approx(r.mean_s)
    assert r.failures_vgs == 1 and r.failures_center == 0
    s_c, s_v = 41 * 40.0, 10 * 50 + 10 * 44 + 20 * 41 + 120
    assert r.total_pct.value == pytest.approx(100 * (s_v - s_c) / s_c)
    assert r.total_pct.low <= r.total_pct.value <= r.total_pct.high
    # Without across_mm the flank's scenes stay in the along-axis part; nothing is invented.
    r = regret(*_regret_case(with_across=False))
    assert r.parts["flank pixels"] is None
    assert r.parts["along-axis offset"][0] == pytest.approx(1.5)


def test_iqm_and_probability_of_improvement_on_known_data() -> None:
    assert iqm(np.arange(1.0, 9.0)) == pytest.approx(4.5)  # cuts 1, 2 and 7, 8
    assert iqm([np.nan, 3.0, 3.0, 3.0, 100.0]) == pytest.approx(3.0)
    # VGS faster on scenes 0, 1; slower on 2; a tie on 3 (both failed); faster on 4 (the other
    # failed): (1 + 1 + 0 + 0.5 + 1) / 5.
    wins = win_matrix(np.array([1.0, 2.0, 5.0, 0.0, 9.0]), np.array([1, 1, 1, 0, 1], bool),
                      np.array([2.0, 3.0, 4.0, 0.0, 1.0]), np.array([1, 1, 1, 0, 0], bool))
    assert list(wins) == [1.0, 1.0, 0.0, 0.5, 1.0]
    p, low, high = improvement_probability(np.stack([wins, wins]))
    assert p == pytest.approx(0.7) and low <= 0.7 <= high
    p, low, high = improvement_probability(np.ones((3, 50)))
    assert (p, low, high) == (1.0, 1.0, 1.0)
    times = np.tile(np.arange(1.0, 9.0), (2, 1))
    value, low, high = iqm_interval(times, np.ones_like(times, bool))
    assert value == pytest.approx(4.5) and low <= 4.5 <= high


def test_the_makeup_of_two_runs_averages_exact_splits(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    frames = []
    for run, speed in (("s0", 0.9), ("s1", 0.8)):
        t = rng.uniform(40, 80, 300)
        off = rng.uniform(-50, 50, 300)
        frames += [_table("baseline", _phases(t), offset=off, run=run),
                   _table("vgs", _phases(speed * t), offset=off / 3, run=run)]
    df = pd.concat(frames, ignore_index=True)
    m = gain_makeup("nominal", condition_pairs(df, "nominal"))
    assert m.runs == ("s0", "s1") and m.across is None and m.regrets is None
    assert sum(v for k, v in m.phases.items() if k != "gap") == pytest.approx(m.phases["gap"])
    assert sum(p.part_s for p in m.along) == pytest.approx(m.phases["gap"])
    assert len(m.within_scenes) == 2 and m.within[1] <= m.within[0] <= m.within[2]
    with_across = df.assign(across_mm=np.where(df["policy"] == "vgs", 2.0, 7.0))
    m = gain_makeup("nominal", condition_pairs(with_across, "nominal"))
    assert m.across is not None and [p.site for p in m.across] == list(ACROSS_SITES)
    assert sum(p.part_s for p in m.across) == pytest.approx(m.phases["gap"])


def test_a_centre_on_other_scenes_is_refused() -> None:
    tests = _table("vgs", _phases(np.full(5, 40.0)))
    center = _table("center", _phases(np.full(5, 40.0)))
    assert len(check_center(center, tests, Path("c"))) == 5
    with pytest.raises(ConfigError, match="not the same scenes"):
        check_center(center.assign(seed=center["seed"] + 1), tests, Path("c"))
    with pytest.raises(ConfigError, match="no centre"):
        check_center(tests, tests, Path("c"))


def test_the_report_has_the_makeup_and_the_regret(tmp_path: Path) -> None:
    from vgs.analysis.report import build_report

    run = tmp_path / "run"
    shutil.copytree(DATA, run)
    text = build_report(run).read_text()
    assert "## What the gain is made of" in text and "## Regret against the centre" in text
    assert "across the axis: unavailable" in text  # the stored tables predate across_mm
    assert "paper's gain: total time of its 1000 tests, none reported failed" in text
    table = text.split("## What the gain is made of")[1].split("\n\n")[2]
    rows = [r.split(" | ") for r in table.splitlines()[2:]]
    for col in range(1, len(rows[0])):
        values = [float(r[col].split(" ")[0].strip(" |*")) for r in rows]
        assert sum(values[:-1]) == pytest.approx(values[-1], abs=0.1)  # rows sum to the gap


def test_seeds_says_not_established_when_the_t_interval_crosses_zero() -> None:
    from vgs.analysis.seeds import _interval_verdict

    row = pd.Series({"gain_ci_low": 2.0, "gain_ci_high": 20.0, "gain_t_low": -5.4,
                     "gain_t_high": 35.9})
    assert _interval_verdict(row, "gain").startswith("not established")
    row["gain_t_low"] = 1.0
    assert "established" in _interval_verdict(row, "gain")
    assert not _interval_verdict(row, "gain").startswith("not")


def test_durations_and_moments_in_the_unit_that_fits() -> None:
    from vgs.analysis.sweepfigure import moment_unit
    from vgs.runfolder.common import duration_text

    assert duration_text(7.5) == "7.5 s" and duration_text(76.07) == "76 s"
    assert duration_text(1800) == "30.0 min" and duration_text(7200) == "2.00 h"
    assert moment_unit(np.array([0.02]))[1] == "mN m"
    assert moment_unit(np.array([2.5e-5]))[1] == "uN m"


def test_curves_say_skipped_and_stopped() -> None:
    from vgs.analysis.curves import summarize

    df = pd.DataFrame({"episode": np.arange(10), "grasp_success": True,
                       "assembly_success": False, "assembly_time_s": np.nan,
                       "grasp_offset_mm": 5.0, "reward": 0.3, "failure_reason": "no_assembly"})
    s = summarize(df, 5, 3)["last_window"]
    assert s["assembly_skipped"] and math.isnan(s["assembly_success"])
    df["failure_reason"] = ["cutoff:search"] * 4 + [""] * 6
    df["assembly_success"] = [False] * 4 + [True] * 6
    s = summarize(df, 5, 10)["last_window"]
    assert not s["assembly_skipped"] and s["threshold_stops"] == 4


def test_grasp_sites_read_the_recorded_column_without_replay(monkeypatch) -> None:
    import vgs.analysis.graspsites as gs
    from vgs.config import profile

    def no_replay(*args: object) -> None:
        raise AssertionError("replayed a scene whose across_mm is recorded")

    monkeypatch.setattr(gs, "EpisodeRunner", no_replay)
    df = pd.DataFrame({"policy": "vgs", "condition": "nominal", "seed": [1, 2],
                       "peg_mass_kg": 0.55, "peg_length_mm": 100.0, "row": [3, 4],
                       "col": [5, 6], "grasp_offset_mm": [12.0, -30.0],
                       "across_mm": [-6.0, 2.0], "assembly_success": [True, False]})
    sites = gs.grasp_sites(df, profile("smoke"), progress=False)
    assert list(sites["across_mm"]) == [6.0, 2.0]
    assert list(sites["along_mm"]) == [12.0, -30.0]
    assert "no replay" in gs.sites_table(sites)
