"""The sweep's plan, checks, statistics and moments; results independent of the worker count."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vgs.config import PegConfig, profile
from vgs.errors import ConfigError
from vgs.experiments.sweep import (
    COLUMNS,
    SweepSpec,
    check_spec,
    default_offsets,
    disturbing_moments,
    plan,
    run_sweep,
    summarize,
)


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
        (SweepSpec(offsets=(0.0, 0.045), trials=1), "offsets"),
        (SweepSpec(offsets=(float("nan"),), trials=1), "offsets"),
        (SweepSpec(offsets=(), trials=1), "offsets"),
        (SweepSpec(offsets=(0.035,), trials=1, length_range=0.15), "offsets"),
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
    assert len({t.seed for t in trials}) == 12
    assert plan(spec, nominal) == trials  # deterministic
    seed = int(np.random.SeedSequence([3, 1, 2]).generate_state(1)[0])
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


def test_summarize() -> None:
    rows = [
        {"offset_mm": 0.0, "success": True, "assembly_time_s": 10.0, "adjustments": 2},
        {"offset_mm": 0.0, "success": True, "assembly_time_s": 14.0, "adjustments": 4},
        {"offset_mm": 20.0, "success": False, "assembly_time_s": 90.0, "adjustments": 30},
    ]
    s = summarize(rows)
    assert s[0] == {"offset_mm": 0.0, "n": 2, "successes": 2, "success_rate": 1.0,
                    "time_mean_s": 12.0, "time_std_s": 2.0, "time_min_s": 10.0,
                    "time_max_s": 14.0, "adjustments_mean": 3.0}
    assert s[1]["success_rate"] == 0.0 and s[1]["time_mean_s"] is None


@pytest.mark.slow
def test_results_do_not_depend_on_the_worker_count() -> None:
    cfg = profile("smoke")
    spec = SweepSpec(offsets=(0.0,), trials=2, mass_range=0.1, seed=5)
    one = run_sweep(cfg, spec, workers=1, progress=False)
    two = run_sweep(cfg, spec, workers=2, progress=False)
    assert list(one[0]) == list(COLUMNS)
    assert [r["seed"] for r in one] == [t.seed for t in plan(spec, cfg.cell.peg)]
    assert repr(one) == repr(two)
