"""``vgs/GraspAssemble-v0``: registration, the checkers of Gymnasium and Stable-Baselines3, the
training reward and threshold rule, conditions, mask, rendering and the documented recipes."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import vgs
from vgs.assembly.record import EpisodeRecord
from vgs.config import override, profile
from vgs.envs.grasp_assemble import DEPTH_UNIT, GraspAssembleEnv, make_config
from vgs.errors import ConfigError
from vgs.grasping.actions import peg_mask
from vgs.grasping.rewards import derive_threshold
from vgs.render import gl_available

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"cell.camera.size": 64, "cell.camera.pixel_size": 0.007}
GL, GL_REASON = gl_available()
needs_gl = pytest.mark.skipif(not GL, reason=f"no OpenGL for MuJoCo's renderer: {GL_REASON}")


def small_env(mode: str = "vgs", **kwargs: Any) -> GraspAssembleEnv:
    return GraspAssembleEnv("smoke", mode=mode, overrides=SMALL, **kwargs)


def test_import_vgs_registers_without_torch_or_mujoco() -> None:
    code = ("import sys, vgs, gymnasium; assert 'vgs/GraspAssemble-v0' in gymnasium.registry; "
            "print('torch' in sys.modules, 'mujoco' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.split() == ["False", "False"]
    env = gymnasium.make(vgs.ENV_ID)  # the acceptance line: the paper profile by default
    assert env.unwrapped.cfg.name == "paper"
    assert env.action_space.nvec.tolist() == [1, 224, 224]  # the position action
    env.close()


def test_profile_name_condition_and_overrides() -> None:
    env = gymnasium.make(vgs.ENV_ID, cfg="quick", condition="length",
                         overrides={"cell.peg.mass": 0.6, **SMALL})
    inner = env.unwrapped
    assert inner.cfg.name == "quick" and inner.cfg.cell.peg.mass == 0.6
    assert env.action_space.nvec.tolist() == [1, 64, 64]
    lengths = {env.reset(seed=s)[1]["peg_length_mm"] for s in range(4)}
    nominal = 1000 * inner.cfg.cell.peg.length
    assert len(lengths) == 4 and all(abs(x / nominal - 1) <= 0.15 for x in lengths)
    with pytest.raises(ConfigError, match="profile"):
        GraspAssembleEnv("fast")
    with pytest.raises(ConfigError, match="cell.peg.nope"):
        GraspAssembleEnv("smoke", overrides={"cell.peg.nope": 1})
    with pytest.raises(ConfigError, match="condition"):
        GraspAssembleEnv("smoke", condition="heavy")


def test_mask_and_depth_channel() -> None:
    env = small_env()
    obs, info = env.reset(seed=3)
    hm = env.heightmap
    assert obs["depth"].shape == (64, 64, 1) and obs["depth"].dtype == np.uint8
    np.testing.assert_allclose(obs["depth"][..., 0] * DEPTH_UNIT, hm.depth, atol=DEPTH_UNIT / 2)
    assert 25 <= obs["depth"].max() * DEPTH_UNIT * 1000 <= 32  # the lying peg, 30 mm
    np.testing.assert_array_equal(info["action_mask"], peg_mask(hm.depth))
    assert 0 < info["action_mask"].sum() < 0.1 * 64 * 64


def test_reward_and_threshold_follow_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """Training's rule, episode by episode: no r_AM before a time is known, the running median
    of the exploration phase (smoke: 2 episodes), frozen after it."""
    env = small_env()
    times = iter([50.0, 30.0, 35.0, 45.0])

    def fake_run(seed: int, policy: Any, peg: Any = None, trace: bool = False,
                 assemble: bool = True) -> tuple:
        return EpisodeRecord(seed=seed, peg_mass=0.55, peg_length=0.1, grasp_success=True,
                             grasp_offset=0.0, success=True, assembly_time=next(times)), None, None

    monkeypatch.setattr(env.runner, "run", fake_run)
    env.reset(seed=0)
    rewards, thresholds = [], []
    for i in range(4):
        if i:
            env.reset()  # every step ends an episode
        _, reward, terminated, _, info = env.step(np.array([0, 30, 30]))
        assert terminated and info["r_grasp"] == 0.3
        rewards.append(reward)
        thresholds.append(env.threshold_s)
    assert thresholds == [50.0, derive_threshold([50.0, 30.0], 50.0), 40.0, 40.0]
    # 50 < 50 is false; 30 < 40 (median after two); 35 < 40 frozen; 45 > 40
    assert rewards == pytest.approx([0.3, 1.0, 1.0, 0.3])
    baseline = small_env("baseline")
    times = iter([50.0, 30.0])
    monkeypatch.setattr(baseline.runner, "run", fake_run)
    baseline.reset(seed=0)
    first = baseline.step(np.array([0, 1, 1]))[1]
    baseline.reset()
    assert [first, baseline.step(np.array([0, 1, 1]))[1]] == [0.3, 0.3]
    env.reset(seed=0)  # a seeded reset starts the run over
    assert env.threshold_s is None and env.episodes == 0


@pytest.mark.slow
def test_checkers_pass_without_warnings() -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gymnasium.make(vgs.ENV_ID, cfg="smoke", overrides=SMALL)
        check_env(env.unwrapped, skip_render_check=not GL)  # with GL: rgb_array checked too
        sb3_check_env(env.unwrapped, warn=True)


@pytest.mark.slow
def test_step_returns_record_and_reward() -> None:
    env = small_env(threshold_s=1000.0)
    obs, info = env.reset(seed=3)
    rows, cols = np.nonzero(info["action_mask"])
    _, reward, terminated, truncated, info = env.step((0, int(rows.mean()), int(cols.mean())))
    record = info["record"]
    assert terminated and not truncated
    expected = ((0.3 if record["grasp_success"] else 0.0)
                + (0.7 if record["assembly_success"] else 0.0))
    assert reward == pytest.approx(expected)
    assert all(not (isinstance(v, float) and math.isnan(v)) for v in record.values())


def _doc_blocks() -> list[str]:
    text = (ROOT / "docs" / "agents.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)


@pytest.mark.slow
def test_documented_sb3_recipe_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """docs/agents.md's MaskablePPO recipe, its rollout and steps cut to 4."""
    pytest.importorskip("sb3_contrib")
    sb3, _ = _doc_blocks()
    short = sb3.replace("STEPS = 2048", "STEPS = 4").replace("n_steps=128, batch_size=64",
                                                              "n_steps=4, batch_size=4")
    assert "STEPS = 4\n" in short and "n_steps=4," in short  # both were found
    namespace: dict[str, Any] = {}
    exec(compile(short, "docs/agents.md", "exec"), namespace)
    assert namespace["model"].num_timesteps == 4
    assert namespace["env"].action_masks()[namespace["action"]]
    assert re.search(r"reward 0\.3, grasped: True", capsys.readouterr().out)


@pytest.mark.slow
def test_documented_vector_recipe_runs(capsys: pytest.CaptureFixture[str]) -> None:
    """docs/agents.md's vectorised recipe: 2 x 2 steps, every step an episode, reset at once."""
    _, vector = _doc_blocks()
    namespace: dict[str, Any] = {}
    exec(compile(vector, "docs/agents.md", "exec"), namespace)
    infos = namespace["infos"]
    assert infos["final_info"]["record"]["grasp_success"].shape == (2,)
    assert infos["action_mask"].shape == (2, 224, 224) and infos["action_mask"].any()
    assert namespace["obs"]["depth"].shape == (2, 224, 224, 1)
    assert len(capsys.readouterr().out.strip().splitlines()) == 2


@needs_gl
def test_render_rgb_array() -> None:
    env = gymnasium.make(vgs.ENV_ID, cfg="smoke", overrides=SMALL, render_mode="rgb_array",
                         render_width=160, render_height=120)
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8 and frame.std() > 10
    env.close()


@needs_gl
@pytest.mark.slow
def test_record_video_records_an_episode(tmp_path: Path) -> None:
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(gymnasium.make(vgs.ENV_ID, cfg="smoke", overrides=SMALL,
                                     render_mode="rgb_array", render_width=160,
                                     render_height=120),
                      str(tmp_path / "videos"), episode_trigger=lambda e: True,
                      disable_logger=True)
    obs, info = env.reset(seed=0)
    rows, cols = np.nonzero(info["action_mask"])
    env.step((0, int(rows.mean()), int(cols.mean())))
    env.close()
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000


def test_no_render_mode_is_refused_politely() -> None:
    with pytest.raises(ConfigError, match="render_mode"):
        GraspAssembleEnv("smoke", render_mode="human")
    env = small_env()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_bad_action_is_one_config_error() -> None:
    env = small_env()
    env.reset(seed=0)
    with pytest.raises(ConfigError, match="action"):
        env.step(np.array([0, 64, 0]))


def test_config_object_still_accepted() -> None:
    cfg = override(profile("smoke"), "cell.camera.size", 32)
    assert GraspAssembleEnv(cfg).observation_space["color"].shape == (32, 32, 3)


def test_bad_actions_and_a_step_after_the_end_are_refused(monkeypatch) -> None:
    """Actions of the wrong type, shape or range raise a clear error (no truncation of
    fractions, booleans or negatives); a step after the episode ended needs a reset;
    overrides get the command line's checks."""
    env = small_env("vgs")
    record = EpisodeRecord(seed=0, peg_mass=0.55, peg_length=0.1, grasp_success=False)
    monkeypatch.setattr(env.runner, "run", lambda *a, **k: (record, None, None))
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.step(np.array([0, 1, 1]))
    env.reset(seed=0)
    for bad, words in (((0, 1.5, 1), "integers"), ((True, 1, 1), "integers"),
                       ((0, -1, 1), "outside"), ((0, 1), "shape"), ("abc", "shape"),
                       (np.zeros((3, 1), int), "shape"), ((0, 10**6, 1), "outside")):
        with pytest.raises(ConfigError, match=words):
            env.step(bad)
    env.step(np.array([0, 1, 1]))
    with pytest.raises(gymnasium.error.ResetNeeded, match="ended"):
        env.step(np.array([0, 1, 1]))
    for overrides, field in (({"cell.peg.mass": True}, "cell.peg.mass"),
                             ({"cell.camera.size": 60000}, "cell.camera.size"),
                             ({"train.episodes": 10**30}, "train.episodes"),
                             ({"cell.peg.length": 10.0}, "cell.peg.length")):
        with pytest.raises(ConfigError, match=field):
            make_config("smoke", overrides)
