"""The sweep's plan, checks, statistics and moments; results independent of the worker count."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vgs.analysis.sweepfigure import disturbing_moments
from vgs.config import PegConfig, profile
from vgs.errors import ConfigError, VGSError
from vgs.experiments.sweep import (
    COLUMNS,
    SweepSpec,
    check_spec,
    default_offsets,
    paired_analysis,
    plan,
    read_journal,
    read_sweep_journal,
    run_sweep,
    summarize,
)
from vgs.runfolder.journal import encode_row


def test_default_offsets_span_the_graspable_length() -> None:
    offsets = default_offsets(PegConfig(), 9)
    assert len(offsets) == 9
    assert offsets[0] == pytest.approx(-0.035) and offsets[-1] == pytest.approx(0.035)
    assert offsets[4] == pytest.approx(0.0)
    assert default_offsets(PegConfig(), 1) == (0.0,)
    # With a length range the span fits the shortest peg: 85 mm -> +-27.5 mm.
    assert default_offsets(PegConfig(), 3, 0.15)[-1] == pytest.approx(0.0275)


@pytest.mark.parametrize(
    ("spec", "field"),
    [
        (SweepSpec(offsets=(0.0, 0.051), trials=1), "offsets"),
        (SweepSpec(offsets=(float("nan"),), trials=1), "offsets"),
        (SweepSpec(offsets=(), trials=1), "offsets"),
        (SweepSpec(offsets=(0.043,), trials=1, length_range=0.15), "offsets"),
        (SweepSpec(offsets=(0.0,), trials=0), "trials"),
        (SweepSpec(offsets=(0.0,), trials=1, mass_range=1.0), "mass_range"),
        (SweepSpec(offsets=(0.0,), trials=1, length_range=0.6), "length_range"),
    ],
)
def test_bad_sweeps_name_their_field(spec: SweepSpec, field: str) -> None:
    with pytest.raises(ConfigError) as info:
        check_spec(spec, profile("paper").cell)
    assert info.value.field == field


def test_plan_seeds_and_pegs() -> None:
    nominal = PegConfig()
    spec = SweepSpec(offsets=(-0.02, 0.0, 0.02), trials=4, mass_range=0.15, length_range=0.15,
                     seed=3)
    trials = plan(spec, nominal)
    assert [t.index for t in trials] == list(range(12))
    assert [(t.offset_index, t.trial) for t in trials[:5]] == [(0, 0), (0, 1), (0, 2), (0, 3),
                                                                (1, 0)]
    # Paired: trial t is the same scene (seed and peg) at every offset.
    assert len({t.seed for t in trials}) == 4
    for t in trials:
        twin = trials[t.trial]
        assert (t.seed, t.peg) == (twin.seed, twin.peg)
    assert plan(spec, nominal) == trials  # deterministic
    seed = int(np.random.SeedSequence([3, 2]).generate_state(1)[0])
    assert trials[6].seed == seed
    for t in trials:
        length_factor = t.peg.length / nominal.length
        mass_factor = t.peg.mass / (nominal.mass * length_factor)
        assert 0.85 <= length_factor <= 1.15 and 0.85 <= mass_factor <= 1.15
        assert t.peg.diameter == nominal.diameter
    nominal_trials = plan(SweepSpec(offsets=(0.0,), trials=2), nominal)
    assert all(t.peg == nominal for t in nominal_trials)


def test_disturbing_moments_follow_eq_2_and_3() -> None:
    cfg = profile("paper")
    a = cfg.assembly
    m_g, m_i = disturbing_moments(cfg, np.array([0.0, -0.02, 0.035]))
    m = cfg.cell.peg.mass
    assert m_g[0] == 0.0 and m_i[0] == 0.0
    assert m_g[2] == pytest.approx(m * 9.81 * 0.035 * math.sin(math.radians(a.search_tilt_deg)))
    accel = (2 * math.pi / a.wiggle_period) ** 2 * math.radians(a.wiggle_amplitude_deg)
    assert m_i[1] == pytest.approx(0.5 * m * 0.02**2 * accel)


def _row(offset: float, trial: int, ok: bool, time: float, align: float = 1.0,
         retries: int = 0) -> dict[str, object]:
    return {"offset_mm": offset, "trial": trial, "assembly_success": ok,
            "assembly_time_s": time,
            "time_align_s": align, "adjustments": 2, "retries": retries,
            "failure_reason": "" if ok else "timeout:align"}


def test_summarize() -> None:
    rows = [_row(0.0, 0, True, 10.0), _row(0.0, 1, True, 14.0, retries=1),
            _row(20.0, 0, False, 90.0)]
    s = summarize(rows)
    assert s[0]["n"] == 2 and s[0]["successes"] == 2 and s[0]["success_rate"] == 1.0
    assert s[0]["time_mean_s"] == 12.0 and s[0]["time_std_s"] == 2.0
    assert s[0]["retry_rate"] == 0.5 and s[0]["time_align_mean_s"] == 1.0
    assert s[1]["success_rate"] == 0.0 and s[1]["time_mean_s"] is None


def test_paired_analysis_recovers_a_known_slope() -> None:
    """Times T = 20 + 0.5 |offset| + scene noise (+ a little noise per episode at one offset):
    the scene noise cancels in the paired differences, so they are exact where no episode
    noise is added, and the slope's interval holds 0.5 s/mm."""
    rng = np.random.default_rng(0)
    noise = rng.normal(0.0, 5.0, 30)
    extra = rng.normal(0.0, 1.0, 30)
    rows = [_row(o, t, True, 20.0 + 0.5 * abs(o) + noise[t] + (extra[t] if o < 0 else 0.0),
                 align=2.0 + 0.1 * abs(o))
            for t in range(30) for o in (-20.0, 0.0, 20.0)]
    out = paired_analysis(rows, resamples=300)
    diff = {e["offset_mm"]: e for e in out["vs_center"]}
    assert diff[20.0]["time_diff_s"] == pytest.approx(10.0)
    assert diff[-20.0]["align_diff_s"] == pytest.approx(2.0)
    lo, hi = diff[20.0]["time_diff_ci_s"]
    assert lo == pytest.approx(10.0) and hi == pytest.approx(10.0)
    lo, hi = out["slope"]["time_ci_s_per_mm"]
    assert lo < 0.5 < hi and out["slope"]["time_s_per_mm"] == pytest.approx(0.5, abs=0.05)
    sym = out["symmetry"][0]
    assert sym["abs_offset_mm"] == 20.0 and sym["plus_success"] == [30, 30]
    assert sym["plus_time_s"] == pytest.approx(sym["minus_time_s"], abs=1.0)
    assert sym["minus_time_ci_s"][0] < sym["plus_time_s"] < sym["minus_time_ci_s"][1]


def test_sweep_journal_resumes_and_refuses_another_sweep(tmp_path) -> None:
    spec = SweepSpec(offsets=(0.0, 0.01), trials=2, seed=1)
    trials = plan(spec, PegConfig())
    journal = tmp_path / "journal.jsonl"
    row = {"index": 1, "offset_mm": 0.0, "peg_mass_kg": trials[1].peg.mass,
           "peg_length_mm": trials[1].peg.length * 1000, "seed": trials[1].seed,
           "assembly_time_s": None, "assembly_success": False}
    journal.write_text(encode_row(row) + '{"index": 2, "off')  # torn last line
    rows = read_journal(journal, trials)
    assert list(rows) == [1] and math.isnan(rows[1]["assembly_time_s"])
    # a row without its checksum: refused, unless the folder predates the rule (any_legacy)
    journal.write_text(json.dumps(row) + "\n")
    with pytest.raises(VGSError, match="crc32"):
        read_journal(journal, trials)
    assert list(read_journal(journal, trials, any_legacy=True)) == [1]
    journal.write_text(encode_row(row).rstrip("\n"))  # killed between the row and its newline
    rows, lines = read_sweep_journal(journal, trials)
    assert list(rows) == [1] and lines.unterminated and not lines.cut
    journal.write_text(encode_row(row) * 2)
    with pytest.raises(VGSError, match="repeats trial 1"):
        read_journal(journal, trials)
    # a row written before the column vocabulary (mass_kg, length_mm, success, bare NaN)
    legacy = {"index": 1, "offset_mm": 0.0, "mass_kg": trials[1].peg.mass,
              "length_mm": trials[1].peg.length * 1000, "seed": trials[1].seed,
              "assembly_time_s": math.nan, "success": True}
    journal.write_text(json.dumps(legacy) + "\n")
    rows = read_journal(journal, trials, any_legacy=True)
    assert rows[1]["assembly_success"] is True and rows[1]["peg_mass_kg"] == trials[1].peg.mass
    assert math.isnan(rows[1]["assembly_time_s"]) and "success" not in rows[1]
    journal.write_text(encode_row({**row, "seed": 7}))
    with pytest.raises(VGSError, match="another sweep"):
        read_journal(journal, trials)


@pytest.mark.slow
def test_results_do_not_depend_on_the_worker_count() -> None:
    cfg = profile("smoke")
    spec = SweepSpec(offsets=(0.0,), trials=2, mass_range=0.1, seed=5)
    one = run_sweep(cfg, spec, workers=1, progress=False)
    two = run_sweep(cfg, spec, workers=2, progress=False)
    assert list(one[0]) == list(COLUMNS)
    assert [r["seed"] for r in one] == [t.seed for t in plan(spec, cfg.cell.peg)]
    assert repr(one) == repr(two)


def test_every_published_journal_reads_under_the_integrity_rule() -> None:
    """Each journal committed under docs/results carries a checksum on every row, or is one of
    the journals published before the rule (vgs.runfolder.journal.PUBLISHED, by SHA-256)."""
    from pathlib import Path

    from vgs.runfolder.journal import read_lines

    root = Path(__file__).resolve().parents[1] / "docs" / "results"
    journals = sorted(root.rglob("journal.jsonl"))
    assert journals
    for path in journals:
        assert read_lines(path).rows, path  # refused (CorruptFileError) otherwise
