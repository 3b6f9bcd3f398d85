"""The two standard-deviation conventions of the results tables (vgs.analysis.stats)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vgs.analysis.stats import population_std, sample_std


def test_sample_and_population_std() -> None:
    times = [10.0, 14.0, 12.0, 20.0]
    assert sample_std(times) == pytest.approx(float(np.std(times, ddof=1)))
    assert population_std(times) == pytest.approx(float(np.std(times)))
    assert sample_std(times) / population_std(times) == pytest.approx(math.sqrt(4 / 3))


def test_too_few_values_give_nan() -> None:
    assert math.isnan(sample_std([3.0])) and math.isnan(sample_std([]))
    assert population_std([3.0]) == 0.0 and math.isnan(population_std([]))


def test_the_tables_use_their_published_convention() -> None:
    """Evaluation summaries divide by n - 1, the sweep's by n (docs/results re-derive)."""
    import pandas as pd

    from vgs.analysis.stats import summarize as evaluation_summary
    from vgs.experiments.sweep import summarize as sweep_summary

    times = [10.0, 14.0, 12.0]
    df = pd.DataFrame({"assembly_success": True, "grasp_success": True, "assembly_time_s": times,
                       "grasp_offset_mm": 0.0, "failure_reason": ""})
    assert evaluation_summary(df)["time_std_s"] == pytest.approx(2.0)
    rows = [{"offset_mm": 0.0, "assembly_success": True, "assembly_time_s": t, "time_align_s": 1.0,
             "adjustments": 0, "failure_reason": ""} for t in times]
    assert sweep_summary(rows)[0]["time_std_s"] == pytest.approx(math.sqrt(8 / 3))
