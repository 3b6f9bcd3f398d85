"""Standard agents on ``vgs/GraspAssemble-v0``: ``action_masks()`` for sb3-contrib's MaskablePPO,
the flat action with the exact mask, grasp-only episodes and the SB3 logging callback."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest

import vgs
from vgs.assembly.record import EpisodeRecord
from vgs.envs.grasp_assemble import GraspAssembleEnv
from vgs.envs.masking import FlatGraspAction
from vgs.errors import ConfigError

SMALL = {"cell.camera.size": 64, "cell.camera.pixel_size": 0.005}
ROTATION = {**SMALL, "network.action": "rotation"}  # smoke: R = 4 maps


def grasp_only(overrides: dict[str, Any] = SMALL) -> GraspAssembleEnv:
    return GraspAssembleEnv("smoke", mode="baseline", overrides=overrides, assemble=False)


def test_action_masks_per_dimension_agree_with_the_info_mask() -> None:
    env = grasp_only(ROTATION)
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.action_masks()
    _, info = env.reset(seed=3)
    mask = info["action_mask"]
    masks = env.action_masks()
    assert masks.dtype == np.bool_ and masks.shape == (4 + 64 + 64,)
    assert masks[:4].all()
    np.testing.assert_array_equal(masks[4:68], mask.any(axis=1))
    np.testing.assert_array_equal(masks[68:], mask.any(axis=0))
    assert 0 < masks[4:].sum() < 64  # the peg's rows and columns, not all


def test_flat_action_has_the_exact_mask_and_round_trips() -> None:
    env = FlatGraspAction(grasp_only(ROTATION))
    _, info = env.reset(seed=3)
    assert env.action_space == gymnasium.spaces.Discrete(4 * 64 * 64)
    masks = env.action_masks()
    assert masks.dtype == np.bool_ and masks.shape == (4 * 64 * 64,)
    np.testing.assert_array_equal(masks.reshape(4, 64, 64), np.stack([info["action_mask"]] * 4))
    for k, (row, col) in zip((0, 3), np.argwhere(info["action_mask"])[[0, -1]], strict=True):
        flat = env.flat(k, int(row), int(col))
        assert masks[flat]
        np.testing.assert_array_equal(env.action(np.int64(flat)), [k, row, col])
    for bad in (-1, 4 * 64 * 64, 1.5, [1, 2], True):
        with pytest.raises(ConfigError, match="action"):
            env.action(bad)
    with pytest.raises(ConfigError, match="MultiDiscrete"):
        FlatGraspAction(gymnasium.make("CartPole-v1"))


def test_flat_action_grasps_where_the_multidiscrete_one_does() -> None:
    flat_env, plain = FlatGraspAction(grasp_only()), grasp_only()
    _, info = flat_env.reset(seed=5)
    plain.reset(seed=5)
    row, col = (int(v) for v in np.argwhere(info["action_mask"]).mean(axis=0))
    a = flat_env.step(flat_env.flat(0, row, col))[4]["record"]
    b = plain.step(np.array([0, row, col]))[4]["record"]
    assert a == b and a["grasp_success"]


def test_grasp_only_episode_rewards_the_grasp_alone() -> None:
    env = GraspAssembleEnv("smoke", mode="vgs", overrides=SMALL, assemble=False)
    _, info = env.reset(seed=5)
    row, col = (int(v) for v in np.argwhere(info["action_mask"]).mean(axis=0))
    _, reward, terminated, _, info = env.step(np.array([0, row, col]))
    record = info["record"]
    assert terminated and record["grasp_success"] and record["failure_reason"] == "no_assembly"
    assert record["assembly_time_s"] is None and reward == pytest.approx(0.3)
    with pytest.raises(ConfigError, match="assemble"):
        GraspAssembleEnv("smoke", overrides=SMALL, assemble="no")  # type: ignore[arg-type]


def test_maskable_ppo_steps_on_the_masks() -> None:
    sb3_contrib = pytest.importorskip("sb3_contrib")
    from stable_baselines3.common.env_checker import check_env

    env = FlatGraspAction(gymnasium.make(vgs.ENV_ID, cfg="smoke", mode="baseline",
                                         assemble=False, overrides=SMALL))
    check_env(env, warn=True)
    model = sb3_contrib.MaskablePPO("MultiInputPolicy", env, n_steps=4, batch_size=4, n_epochs=1,
                                    seed=0)
    model.learn(total_timesteps=4)
    assert model.num_timesteps == 4
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        action, _ = model.predict(obs, action_masks=env.action_masks())
        assert env.action_masks()[int(action)]  # on the peg, whatever the untrained weights
    # the MultiDiscrete action with the per-dimension masks
    plain = grasp_only()
    multi = sb3_contrib.MaskablePPO("MultiInputPolicy", plain, n_steps=4, batch_size=4,
                                    n_epochs=1, seed=0)
    multi.learn(total_timesteps=4)
    obs, info = plain.reset(seed=1)
    k, row, col = multi.predict(obs, action_masks=plain.action_masks())[0]
    assert info["action_mask"][row].any() and info["action_mask"][:, col].any()


def test_callback_logs_the_records(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import configure

    from vgs.envs.callbacks import EpisodeLogger, episode_scalars

    records = iter([
        EpisodeRecord(seed=0, peg_mass=0.55, peg_length=0.1, grasp_success=True,
                      grasp_offset=-0.004, success=True, assembly_time=50.0),
        EpisodeRecord(seed=1, peg_mass=0.55, peg_length=0.1, failure_reason="grasp"),
        EpisodeRecord(seed=2, peg_mass=0.55, peg_length=0.1, grasp_success=True,
                      grasp_offset=0.010, failure_reason="timeout:search"),
        EpisodeRecord(seed=3, peg_mass=0.55, peg_length=0.1, grasp_success=True,
                      grasp_offset=0.002, success=True, assembly_time=30.0),
    ])
    env = GraspAssembleEnv("smoke", overrides=SMALL)
    monkeypatch.setattr(env.runner, "run", lambda *a, **k: (next(records), None, None))
    model = PPO("MultiInputPolicy", env, n_steps=4, batch_size=4, n_epochs=1, seed=0)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(total_timesteps=4, callback=EpisodeLogger())
    with open(tmp_path / "progress.csv") as f:
        row = next(csv.DictReader(f))
    logged = {k: float(v) for k, v in row.items() if k.startswith("vgs/")}
    assert logged == pytest.approx({"vgs/grasp_success": 0.75, "vgs/abs_grasp_offset_mm": 16 / 3,
                                    "vgs/assembly_success": 2 / 3, "vgs/assembly_time_s": 40.0})
    no_assembly = {"grasp_success": True, "grasp_offset_mm": 3.0, "assembly_success": False,
                   "failure_reason": "no_assembly", "assembly_time_s": None}
    assert episode_scalars(no_assembly) == {"grasp_success": 1.0, "abs_grasp_offset_mm": 3.0}
