"""Training: a killed run resumes from its checkpoint with the same episode count and RNG, in
its folder or moved to another; the replay's re-rendered heightmaps are the ones it stored."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from vgs.config import ExperimentConfig, override, profile, to_dict
from vgs.errors import ConfigError
from vgs.experiments import train as train_mod


def tiny_config() -> ExperimentConfig:
    cfg = profile("smoke")
    cfg = override(cfg, "cell.camera.size", 64)
    cfg = override(cfg, "cell.camera.pixel_size", 0.007)
    cfg = override(cfg, "train.episodes", 3)
    cfg = override(cfg, "agent.random_episodes", 1)
    return override(cfg, "train.checkpoint_every", 1)


def rows(run: Path) -> list[dict[str, str]]:
    with (run / "episodes.csv").open(newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(f)]


@pytest.fixture(scope="module")
def full_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[int, Any]]:
    """An uninterrupted run of :func:`tiny_config` (real physics) and the heightmaps each
    episode stored in the replay, by scene seed."""
    stored: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    original = train_mod.ReplayBuffer.add

    def recording_add(self, transition, surprise):
        stored[transition.scene] = (transition.color.copy(), transition.depth.copy())
        return original(self, transition, surprise)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(train_mod.ReplayBuffer, "add", recording_add)
        run = train_mod.train(tiny_config(), "vgs", tmp_path_factory.mktemp("full") / "run",
                              progress=False)
    return run, stored


def _killed_at_third_episode(out: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = {"n": 0}
    original = train_mod.EpisodeRunner.run

    def dying_run(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt  # the session is killed during the third episode
        return original(self, *args, **kwargs)

    monkeypatch.setattr(train_mod.EpisodeRunner, "run", dying_run)
    with pytest.raises(KeyboardInterrupt):
        train_mod.train(tiny_config(), "vgs", out, progress=False)
    monkeypatch.setattr(train_mod.EpisodeRunner, "run", original)
    assert [r["episode"] for r in rows(out)] == ["0", "1"]


@pytest.mark.slow
def test_killed_run_resumes_where_it_stopped(tmp_path: Path, monkeypatch, full_run) -> None:
    _killed_at_third_episode(tmp_path / "resumed", monkeypatch)
    train_mod.train(tiny_config(), "vgs", tmp_path / "resumed", progress=False)

    resumed = rows(tmp_path / "resumed")
    assert [r["episode"] for r in resumed] == ["0", "1", "2"]
    assert resumed == rows(full_run[0])  # same seeds, actions, rewards and losses


@pytest.mark.slow
def test_a_checkpoint_moved_to_another_folder_resumes_to_the_same_table(
        tmp_path: Path, monkeypatch, full_run) -> None:
    """The folder moves (another machine's checkout) and the resumed run renders every replayed
    heightmap afresh (no cache): the table is the uninterrupted run's."""
    _killed_at_third_episode(tmp_path / "here" / "run", monkeypatch)
    moved = tmp_path / "elsewhere" / "run"
    moved.parent.mkdir()
    shutil.move(tmp_path / "here" / "run", moved)
    monkeypatch.setattr(train_mod, "REPLAY_CACHE", 0)
    replayed = {"n": 0}
    original = train_mod.ReplayBuffer.get

    def counting_get(self, index):
        replayed["n"] += 1
        return original(self, index)

    monkeypatch.setattr(train_mod.ReplayBuffer, "get", counting_get)
    train_mod.train(tiny_config(), "vgs", moved, progress=False)
    assert replayed["n"] == 1  # episode 2's replay, its heightmaps rendered afresh
    assert rows(moved) == rows(full_run[0])


@pytest.mark.slow
def test_a_resumed_run_keeps_the_torch_threads_it_started_with(
        tmp_path: Path, monkeypatch, full_run) -> None:
    """Another thread count sums in another order; run.json keeps the first, and a resume
    asking for another still computes the uninterrupted run's table."""
    import json

    _killed_at_third_episode(tmp_path / "run", monkeypatch)
    recorded = json.loads((tmp_path / "run" / "run.json").read_text())["torch_threads"]
    seen: list[int] = []
    monkeypatch.setattr(train_mod.torch, "set_num_threads", seen.append)
    train_mod.train(tiny_config(), "vgs", tmp_path / "run", progress=False,
                    threads=recorded + 1)
    assert seen == [recorded]
    assert rows(tmp_path / "run") == rows(full_run[0])


@pytest.mark.slow
def test_re_rendered_replay_heightmaps_equal_the_stored_ones(full_run) -> None:
    from vgs.grasping.agent import GraspAgent
    from vgs.grasping.replay import ReplayBuffer

    run, stored = full_run
    cfg = tiny_config()
    runner = train_mod.EpisodeRunner(cfg)  # a fresh cell, as on another machine
    replay = ReplayBuffer(cfg.agent.replay_capacity, render=train_mod.scene_renderer(runner),
                          cache_size=0)
    agent = GraspAgent(cfg.network, cfg.agent, seed=cfg.seed)
    train_mod.load_checkpoint(run / "checkpoint.pt", agent, replay, root_seed=cfg.seed)
    assert len(replay) == 3 and set(replay.state_dict()["arrays"]) >= {"scene"}
    assert "color" not in replay.state_dict()["arrays"]  # the checkpoint holds no maps
    runner.run(train_mod.episode_seed(cfg.seed, 7), lambda hm: train_mod.pixel_command(
        hm, 32, 32, 0.0))  # the cell has just run an episode: rendering must not care
    for slot in reversed(range(len(replay))):
        t = replay.get(slot)
        color, depth = stored[t.scene]
        assert t.scene == train_mod.episode_seed(cfg.seed, slot)
        assert t.color.tobytes() == color.tobytes() and t.depth.tobytes() == depth.tobytes()


def test_mode_mismatch_on_resume_is_an_error(tmp_path: Path) -> None:
    (tmp_path / "run.json").write_text(json.dumps({"mode": "baseline",
                                                   "config": to_dict(tiny_config())}))
    with pytest.raises(ConfigError, match="mode"):
        train_mod.train(tiny_config(), "vgs", tmp_path, progress=False)


def test_unknown_mode_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="mode"):
        train_mod.train(tiny_config(), "greedy", tmp_path, progress=False)


def test_action_to_command_maps_closing_direction_to_pad_heading() -> None:
    import math

    import numpy as np

    from vgs.grasping.agent import GraspAction
    from vgs.sim.camera import Heightmap

    hm = Heightmap(np.zeros((8, 8, 3), np.uint8), np.zeros((8, 8), np.float32), (0.0, 0.0), 0.01)
    action = GraspAction(rotation=0, row=2, col=5, angle=0.0, q_value=0.0, explored=False,
                         q_map=None)
    cmd = train_mod.action_to_command(action, hm)
    assert (cmd.x, cmd.y) == pytest.approx((0.055, 0.025))
    # Closing along +x (theta = 0) means the pads' long side lies along y.
    assert math.cos(cmd.yaw) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.slow
def test_parallel_episodes_are_deterministic(tmp_path: Path) -> None:
    """K = 2 worker processes: the same table twice; its first episode (chosen before any
    update, with the generator in the same state) is the sequential run's first episode."""
    cfg = override(override(tiny_config(), "train.checkpoint_every", 2), "train.episodes", 4)
    sequential = train_mod.train(cfg, "vgs", tmp_path / "k1", progress=False)
    cfg2 = override(cfg, "train.parallel_episodes", 2)
    a = rows(train_mod.train(cfg2, "vgs", tmp_path / "k2a", progress=False))
    b = rows(train_mod.train(cfg2, "vgs", tmp_path / "k2b", progress=False))
    assert [r["episode"] for r in a] == ["0", "1", "2", "3"]
    assert a == b
    assert a[0] == rows(sequential)[0]


def test_checkpoints_must_fall_on_batch_ends() -> None:
    with pytest.raises(ConfigError, match="checkpoint_every"):
        override(override(tiny_config(), "train.checkpoint_every", 3),
                 "train.parallel_episodes", 2)


@pytest.mark.slow
def test_a_run_carried_through_git_resumes_and_its_finished_runs_stay_done(
        tmp_path: Path, monkeypatch, full_run) -> None:
    """``scripts/carry.sh``: a folder with a finished and an unfinished training run, packed and
    unpacked elsewhere. The finished run is kept as its final network (no checkpoint) and
    counts as done; the unfinished one resumes to the uninterrupted run's table."""
    import subprocess
    import sys

    import torch

    from vgs.errors import CorruptFileError
    from vgs.rollout.policies import load_trained_agent

    run = tmp_path / "here" / "repro"
    shutil.copytree(full_run[0], run / "train" / "done")
    _killed_at_third_episode(run / "train" / "cut", monkeypatch)
    script = Path(__file__).resolve().parents[1] / "scripts" / "carry.sh"
    env = {"PATH": "/usr/bin:/bin", "VGS": str(Path(sys.executable).parent / "vgs")}
    packed, moved = tmp_path / "carry.tar.xz", tmp_path / "elsewhere" / "repro"
    subprocess.run(["bash", str(script), "pack", str(run), str(packed)], check=True,
                   env={**env, "CARRY_PART_BYTES": "100000000"}, capture_output=True)
    size = packed.stat().st_size
    # over the part size (the repository takes no file over 5 MB) it goes in pieces, and the
    # pieces unpack as the whole file would
    subprocess.run(["bash", str(script), "pack", str(run), str(packed)], check=True,
                   env={**env, "CARRY_PART_BYTES": str(size // 2)}, capture_output=True)
    parts = sorted(tmp_path.glob("carry.tar.xz.part*"))  # (a pack's bytes vary by mtimes)
    assert not packed.exists() and len(parts) >= 2
    assert [p.name[-2:] for p in parts] == [f"{i:02d}" for i in range(len(parts))]
    assert max(p.stat().st_size for p in parts) <= size // 2
    subprocess.run(["bash", str(script), "unpack", str(packed), str(moved)], check=True,
                   env=env, capture_output=True)

    done, cut = moved / "train" / "done", moved / "train" / "cut"
    assert not (done / "checkpoint.pt").exists() and (done / "policy.pt").exists()
    assert (cut / "checkpoint.pt").exists() and not list(moved.rglob("tensorboard"))
    table = (done / "episodes.csv").read_bytes()
    train_mod.train(tiny_config(), "vgs", done, progress=False)  # nothing left to train
    assert (done / "episodes.csv").read_bytes() == table
    with pytest.raises(CorruptFileError, match="no checkpoint.pt to train on"):
        train_mod.train(override(tiny_config(), "train.episodes", 5), "vgs", done,
                        progress=False)
    train_mod.train(tiny_config(), "vgs", cut, progress=False)
    assert rows(cut) == rows(full_run[0])

    # The kept network is the one the checkpoint held (BatchNorm's update counters, which the
    # evaluation network does not use, are not exported).
    _, _, original, n_original = load_trained_agent(full_run[0])
    _, _, kept, n_kept = load_trained_agent(done)
    assert n_kept == n_original == 3
    for name, tensor in original.eva_net.state_dict().items():
        if not name.endswith("num_batches_tracked"):
            assert torch.equal(tensor, kept.eva_net.state_dict()[name]), name
