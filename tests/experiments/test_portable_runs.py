"""Runs that move between machines: compact checkpoints (the replay keeps scene seeds), old
checkpoints that kept heightmaps, hosts that render differently, and published policy folders
that ``vgs evaluate`` loads without the checkpoint. Physics-free (:mod:`experiments.fakes`)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from vgs import checkpoint
from vgs.cli import main
from vgs.config import override, profile

from . import fakes

TRAIN = ["train", "--mode", "vgs", *fakes.CLI_FLAGS]


@pytest.fixture(autouse=True)
def fake_physics(monkeypatch: pytest.MonkeyPatch):
    fakes.use_fake_physics(monkeypatch)


vgs, one_line = fakes.vgs, fakes.one_line


def table(run: Path) -> pd.DataFrame:
    return pd.read_csv(run / "episodes.csv").drop(columns=["wall_s"])


def stopped_after_four(run: Path, capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    """A 6-episode run killed in its fifth episode: checkpoint and table at episode 4."""
    calls = {"n": 0}
    original = fakes.FakeRunner.run

    def dying(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 5:
            raise KeyboardInterrupt
        return original(self, *args, **kwargs)

    monkeypatch.setattr(fakes.FakeRunner, "run", dying)
    assert vgs(capsys, *TRAIN, "--out", str(run))[0] == 130
    monkeypatch.setattr(fakes.FakeRunner, "run", original)
    assert checkpoint.read_meta(run / "checkpoint.pt")["episode"] == 4


def as_old_checkpoint(path: Path, spoil: bool = False) -> None:
    """Rewrite a checkpoint as vgs-checkpoint/2 wrote it: the replay's heightmaps stored, no
    scene seeds (``spoil``: one stored map is not the scene's)."""
    tensors, meta = checkpoint.load(path)
    arrays = tensors["replay_arrays"]
    runner = fakes.FakeRunner(fakes.tiny_config())
    maps = [runner.observe(int(s)) for s in arrays.pop("scene")]
    color = np.stack([hm.color for hm in maps])
    if spoil:
        color[0, 0, 0, 0] ^= 1
    arrays.update(color=torch.from_numpy(color),
                  depth=torch.from_numpy(np.stack([hm.depth for hm in maps])),
                  next_color=None, next_depth=None)
    meta.pop("replay_check")
    meta["format"] = "vgs-checkpoint/2"
    checkpoint.save(path, tensors, meta)
    assert checkpoint.read_meta(path)["format"] == "vgs-checkpoint/2"


def test_a_checkpoint_that_kept_heightmaps_resumes_to_the_same_table(
        tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    assert vgs(capsys, *TRAIN, "--out", str(tmp_path / "full"))[0] == 0
    run = tmp_path / "old"
    stopped_after_four(run, capsys, monkeypatch)
    as_old_checkpoint(run / "checkpoint.pt")
    assert vgs(capsys, *TRAIN, "--out", str(run)) == (0, [])
    pd.testing.assert_frame_equal(table(run), table(tmp_path / "full"))
    assert checkpoint.read_meta(run / "checkpoint.pt")["format"] == checkpoint.FORMAT


def test_an_old_checkpoint_whose_maps_are_not_its_scenes_is_refused(
        tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    run = tmp_path / "old"
    stopped_after_four(run, capsys, monkeypatch)
    as_old_checkpoint(run / "checkpoint.pt", spoil=True)
    before = (run / "checkpoint.pt").read_bytes()
    one_line(*vgs(capsys, *TRAIN, "--out", str(run)), "checkpoint.pt", "episode 0",
             "train again into a new folder")
    assert (run / "checkpoint.pt").read_bytes() == before


def test_a_host_that_renders_the_replay_differently_is_refused(
        tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    run = tmp_path / "run"
    stopped_after_four(run, capsys, monkeypatch)
    original = fakes.FakeRunner.observe

    def other_host(self, seed, peg=None):
        hm = original(self, seed, peg)
        depth = hm.depth.copy()
        depth[0, 0] = np.nextafter(depth[0, 0], np.float32(1))  # one pixel, last bit
        return type(hm)(hm.color, depth, hm.origin, hm.pixel_size)

    monkeypatch.setattr(fakes.FakeRunner, "observe", other_host)
    one_line(*vgs(capsys, *TRAIN, "--out", str(run)), "checkpoint.pt",
             "re-renders its replay heightmaps differently")


def test_a_5000_grasp_light_checkpoint_fits_in_10_mb(tmp_path: Path) -> None:
    """The paper profile with the light backbone (R = 16): networks, optimiser (momentum
    buffers after a first step) and a full replay of 5000 transitions."""
    from vgs.experiments.train import TrainState, save_checkpoint
    from vgs.grasping.agent import DeltaQMonitor, GraspAgent
    from vgs.grasping.replay import ReplayBuffer, Transition

    cfg = override(profile("paper"), "network.backbone", "light")
    assert cfg.agent.replay_capacity == 5000 and cfg.network.num_rotations == 16
    agent = GraspAgent(cfg.network, cfg.agent)
    color, depth = np.zeros((32, 32, 3), np.uint8), np.zeros((32, 32), np.float32)
    agent.update(Transition(color, depth, (0, 5, 5), 1.0))  # the optimiser's momentum buffers
    sizes = {}
    for n in (0, 5000):
        replay = ReplayBuffer(cfg.agent.replay_capacity, render=lambda s: (color, depth))
        for e in range(n):
            replay.add(Transition(color, depth, (e % 16, e % 32, 7), 0.3, scene=e), 0.1)
        save_checkpoint(tmp_path / f"c{n}.pt", agent, replay, TrainState(n),
                        DeltaQMonitor.from_config(cfg.agent))
        sizes[n] = (tmp_path / f"c{n}.pt").stat().st_size
    assert sizes[5000] <= 10_000_000
    assert (sizes[5000] - sizes[0]) / 5000 < 100  # bytes per transition (seed, action, ...)


def test_a_checkpoint_with_a_target_network_still_loads(tmp_path: Path) -> None:
    """Checkpoints written before the target network was removed hold a ``target_net``
    tensor dictionary beside ``eva_net``; it is not read, the evaluation network is restored."""
    from vgs.experiments.train import TrainState, load_checkpoint, save_checkpoint
    from vgs.grasping.agent import DeltaQMonitor, GraspAgent
    from vgs.grasping.replay import ReplayBuffer, Transition

    cfg = profile("smoke")
    color, depth = np.zeros((32, 32, 3), np.uint8), np.zeros((32, 32), np.float32)
    agent = GraspAgent(cfg.network, cfg.agent)
    agent.update(Transition(color, depth, (0, 5, 5), 1.0))
    path = tmp_path / "c.pt"
    save_checkpoint(path, agent, ReplayBuffer(8), TrainState(0), DeltaQMonitor.from_config(
        cfg.agent))
    tensors, meta = checkpoint.load(path)
    assert "target_net" not in tensors
    tensors["target_net"] = GraspAgent(cfg.network, cfg.agent, seed=5).eva_net.state_dict()
    checkpoint.save(path, tensors, meta)
    restored = GraspAgent(cfg.network, cfg.agent, seed=99)
    load_checkpoint(path, restored)
    want, got = agent.eva_net.state_dict(), restored.eva_net.state_dict()
    assert all(torch.equal(want[k], got[k]) for k in want)


def test_a_policy_folder_evaluates_like_its_training_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A published run commits only its final network and run.json (``vgs export-policy RUN
    --out FOLDER``); ``vgs evaluate --policy FOLDER`` on a fresh clone acts as the run did."""
    run = tmp_path / "run"
    assert vgs(capsys, *TRAIN, "--out", str(run))[0] == 0
    assert main(["export-policy", str(run), "--out", str(tmp_path / "export" / "vgs")]) == 0
    assert "vgs evaluate --policy" in capsys.readouterr().out
    clone = tmp_path / "clone" / "docs" / "results" / "smoke" / "vgs"  # what git would check out
    clone.mkdir(parents=True)
    for name in ("run.json", "policy.pt", "policy.json"):
        shutil.copy(tmp_path / "export" / "vgs" / name, clone / name)
    evaluate = ["evaluate", "--episodes", "4", "--workers", "1", *fakes.CLI_FLAGS]
    assert vgs(capsys, *evaluate, "--policy", str(run), "--out", str(tmp_path / "e_run"))[0] == 0
    assert vgs(capsys, *evaluate, "--policy", str(clone), "--out",
               str(tmp_path / "e_pub"))[0] == 0
    a, b = (pd.read_parquet(tmp_path / e / "episodes.parquet").drop(columns="wall_s")
            for e in ("e_run", "e_pub"))
    assert (a["rotation"] >= 0).all()  # the network chose every grasp
    pd.testing.assert_frame_equal(a, b)
    assert pd.read_json(tmp_path / "e_pub" / "meta.json", typ="series")[
        "policy_trained_episodes"] == 6
    # an evaluation begun on the training run resumes on its exported network (scripts/carry.sh
    # moves a finished run as policy.pt): the same weights are the same policy
    assert vgs(capsys, *evaluate, "--episodes", "6", "--policy", str(clone), "--out",
               str(tmp_path / "e_run"))[0] == 0  # (the last --episodes counts)
    c = pd.read_parquet(tmp_path / "e_run" / "episodes.parquet").drop(columns="wall_s")
    pd.testing.assert_frame_equal(c.iloc[:4], a)
    assert len(c) == 6
    # what a folder of the wrong files gets: one line
    (clone / "policy.json").unlink()
    one_line(*vgs(capsys, *evaluate, "--policy", str(clone), "--out", str(tmp_path / "e3")),
             "policy.json")
    one_line(*vgs(capsys, "export-policy", str(run), "--out", str(tmp_path / "e_run")),
             "out")  # a folder holding something else is not overwritten


def test_a_published_reproduction_commits_its_final_networks(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``vgs report DIR --publish DEST`` writes DEST/<mode>/ policy folders beside the tables,
    and ``vgs evaluate --policy DEST/<mode>`` acts as the run's checkpoint does."""
    repro, pub = tmp_path / "repro", tmp_path / "pub"
    flags = [*fakes.CLI_FLAGS, "--set", "reproduce.conditions=(nominal,)"]
    assert vgs(capsys, "reproduce", "--out", str(repro), "--workers", "1", "--stages",
               "train,evaluate,report", *flags)[0] == 0
    capsys.readouterr()
    assert main(["report", str(repro), "--publish", str(pub)]) == 0
    out = capsys.readouterr().out
    assert "with the final networks of 2 runs" in out
    for mode in ("baseline", "vgs"):
        assert sorted(p.name for p in (pub / mode).iterdir()) == ["policy.json", "policy.pt",
                                                                  "run.json"]
    assert not list(pub.rglob("checkpoint.pt"))
    evaluate = ["evaluate", "--episodes", "4", "--workers", "1", *fakes.CLI_FLAGS]
    for policy, folder in ((repro / "train" / "vgs_s0", "a"), (pub / "vgs", "b")):
        assert vgs(capsys, *evaluate, "--policy", str(policy), "--out",
                   str(tmp_path / folder))[0] == 0
    a, b = (pd.read_parquet(tmp_path / e / "episodes.parquet").drop(columns="wall_s")
            for e in "ab")
    pd.testing.assert_frame_equal(a, b)

    # A finished run kept as its final network alone (scripts/carry.sh) publishes the same.
    import torch

    kept = repro / "train" / "baseline_s0"
    assert main(["export-policy", str(kept), "--out", str(kept)]) == 0
    (kept / "checkpoint.pt").unlink()
    assert main(["report", str(repro), "--publish", str(tmp_path / "pub2")]) == 0
    assert "with the final networks of 2 runs" in capsys.readouterr().out
    w1, w2 = (torch.load(d / "baseline" / "policy.pt", weights_only=True)
              for d in (pub, tmp_path / "pub2"))
    assert w1.keys() == w2.keys() and all(torch.equal(w1[k], w2[k]) for k in w1)
