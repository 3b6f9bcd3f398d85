"""Rewards (paper eq. 5) and the threshold."""

from __future__ import annotations

import math

import pytest

from vgs.config import RewardConfig
from vgs.errors import ConfigError
from vgs.grasping.rewards import derive_threshold, grasp_reward

CFG = RewardConfig(grasp=0.3, assembly=0.7)


@pytest.mark.parametrize(
    ("success", "time_s", "mode", "expected"),
    [
        (False, None, "vgs", (0.0, 0.0)),
        (False, None, "baseline", (0.0, 0.0)),
        (False, 5.0, "vgs", (0.0, 0.0)),  # no assembly reward without a grasp
        (True, None, "vgs", (0.3, 0.0)),  # grasped, assembly failed
        (True, None, "baseline", (0.3, 0.0)),
        (True, 5.0, "vgs", (0.3, 0.7)),  # faster than the threshold
        (True, 5.0, "baseline", (0.3, 0.0)),  # the baseline never gets r_AM
        (True, 10.0, "vgs", (0.3, 0.0)),  # equal to the threshold: not faster
        (True, 12.0, "vgs", (0.3, 0.0)),
        (True, 12.0, "baseline", (0.3, 0.0)),
    ],
)
def test_truth_table(success: bool, time_s: float | None, mode: str,
                     expected: tuple[float, float]) -> None:
    assert grasp_reward(success, time_s, 10.0, mode, CFG) == expected


def test_threshold_from_config_and_errors() -> None:
    cfg = RewardConfig(threshold_s=8.0)
    assert grasp_reward(True, 7.0, None, "vgs", cfg) == (0.3, 0.7)
    assert grasp_reward(True, 9.0, None, "vgs", cfg) == (0.3, 0.0)
    with pytest.raises(ConfigError) as err:
        grasp_reward(True, 7.0, None, "vgs", RewardConfig())
    assert err.value.field == "reward.threshold_s"
    # The baseline needs no threshold.
    assert grasp_reward(True, 7.0, None, "baseline", RewardConfig()) == (0.3, 0.0)
    with pytest.raises(ConfigError) as err:
        grasp_reward(True, 7.0, 10.0, "greedy", CFG)
    assert err.value.field == "reward.mode"
    with pytest.raises(ConfigError):
        grasp_reward(True, -1.0, 10.0, "vgs", CFG)


def test_derive_threshold() -> None:
    times = [4.0, 1.0, 3.0, 2.0, math.nan, math.inf]
    assert derive_threshold(times, 50.0) == pytest.approx(2.5)
    assert derive_threshold(times, 25.0) == pytest.approx(1.75)
    with pytest.raises(ConfigError):
        derive_threshold([], 50.0)
    with pytest.raises(ConfigError):
        derive_threshold([math.nan], 50.0)
    with pytest.raises(ConfigError):
        derive_threshold([1.0, 2.0], 100.0)
