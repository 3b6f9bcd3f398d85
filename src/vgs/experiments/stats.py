"""The standard deviations of the results tables, in one place.

Two conventions are in use, each because numbers published under ``docs/results`` were computed
with it and must re-derive unchanged from their stored rows:

* :func:`sample_std` (divisor n - 1): the evaluation tables. ``evaluate.summarize``
  (``summary.json``, ``vgs evaluate``), the report's tables and ``results.csv``, and the spread
  of the gain between training seeds (``vgs seeds``).
* :func:`population_std` (divisor n): the grasp-position sweep. ``sweep.summarize``
  (``summary.json``, the table ``vgs sweep`` prints) and the error bars of ``sweep.png``.

With 20 trials per offset the two differ by a factor sqrt(20 / 19), about 2.6 %.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def sample_std(values: Sequence[float] | np.ndarray) -> float:
    """Standard deviation with divisor n - 1; NaN for fewer than two values."""
    values = np.asarray(values, dtype=float)
    return float(np.std(values, ddof=1)) if values.size > 1 else math.nan


def population_std(values: Sequence[float] | np.ndarray) -> float:
    """Standard deviation with divisor n (NumPy's default); NaN for no values."""
    values = np.asarray(values, dtype=float)
    return float(np.std(values)) if values.size else math.nan
