"""The Gymnasium environment passes Gymnasium's own checker and returns the episode record."""

from __future__ import annotations

import gymnasium
import pytest
from gymnasium.utils.env_checker import check_env

import vgs.envs  # noqa: F401  (registers the environment)
from vgs.config import override, profile
from vgs.envs.grasp_assemble import GraspAssembleEnv


def small_env(mode: str = "vgs") -> GraspAssembleEnv:
    cfg = override(profile("smoke"), "cell.camera.size", 64)
    cfg = override(cfg, "cell.camera.pixel_size", 0.007)
    return GraspAssembleEnv(cfg, mode=mode, threshold_s=1000.0)


@pytest.mark.slow
def test_env_passes_gymnasium_checker() -> None:
    check_env(small_env(), skip_render_check=True)


def test_env_is_registered() -> None:
    assert vgs.envs.ENV_ID in gymnasium.registry


@pytest.mark.slow
def test_step_returns_record_and_reward() -> None:
    env = small_env()
    obs, info = env.reset(seed=3)
    assert obs["color"].shape == (64, 64, 3)
    rows, cols = (obs["depth"] > 0.005).nonzero()
    action = (0, int(rows.mean()), int(cols.mean()))
    _, reward, terminated, truncated, info = env.step(action)
    record = info["record"]
    assert terminated and not truncated
    expected = (0.3 if record["grasp_success"] else 0.0) + (0.7 if record["success"] else 0.0)
    assert reward == pytest.approx(expected)
