"""Evaluation at scale: seeding, determinism across worker counts and backends, failures as
rows, lost workers retried, resume."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from vgs.config import profile, to_dict
from vgs.errors import ConfigError, EpisodeError
from vgs.experiments.evaluate import (
    EvalSpec,
    evaluate,
    evaluate_many,
    plan_episodes,
)
from vgs.experiments.train import TrainState, save_checkpoint
from vgs.grasping.agent import DeltaQMonitor, GraspAgent
from vgs.grasping.replay import ReplayBuffer
from vgs.rollout import episodepool
from vgs.rollout.policies import load_policy, policy_digest

from . import eval_policies, fakes

POLICIES = eval_policies.__name__
VOLATILE = ["wall_s"]


def save_agent(path: Path, agent: GraspAgent, cfg, episode: int) -> None:
    """A training checkpoint of ``agent`` after ``episode`` episodes (empty replay)."""
    save_checkpoint(path, agent, ReplayBuffer(cfg.agent.replay_capacity), TrainState(episode),
                    DeltaQMonitor.from_config(cfg.agent))


@pytest.fixture(scope="module")
def cfg():
    return profile("smoke")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory, cfg) -> Path:
    """A training-run folder holding an untrained network (enough for greedy decisions)."""
    folder = tmp_path_factory.mktemp("run")
    agent = GraspAgent(cfg.network, cfg.agent, seed=5)
    save_agent(folder / "checkpoint.pt", agent, cfg, episode=0)
    (folder / "run.json").write_text(json.dumps({"mode": "vgs", "config": to_dict(cfg)}))
    return folder


def _jobs(run_dir: Path, out: Path) -> list[tuple[EvalSpec, Path]]:
    return [(EvalSpec(str(run_dir), "length", 2, seed=11), out / "greedy"),
            (EvalSpec("random", "mass", 1, seed=11), out / "random")]


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory: pytest.TempPathFactory, cfg, run_dir) -> list[pd.DataFrame]:
    out = tmp_path_factory.mktemp("w1")
    return evaluate_many(cfg, _jobs(run_dir, out), workers=1, progress=False)


def test_plan_is_seeded_by_root_seed_and_index(cfg) -> None:
    a = plan_episodes(cfg, EvalSpec("center", "length", 50, seed=3))
    b = plan_episodes(cfg, EvalSpec("center", "length", 20, seed=3))
    assert a[:20] == b
    assert len({t.seed for t in a}) == 50
    lengths = np.array([t.peg.length for t in a]) / cfg.cell.peg.length
    masses = np.array([t.peg.mass for t in a]) / cfg.cell.peg.mass
    assert lengths.min() >= 0.85 and lengths.max() <= 1.15 and np.ptp(lengths) > 0.2
    np.testing.assert_allclose(masses, lengths)  # the mass follows the volume
    mass = plan_episodes(cfg, EvalSpec("center", "mass", 50, seed=3))
    factors = np.array([t.peg.mass for t in mass]) / cfg.cell.peg.mass
    assert factors.min() >= 0.85 and factors.max() <= 1.15 and np.ptp(factors) > 0.2
    assert all(t.peg.length == cfg.cell.peg.length for t in mass)
    nominal = plan_episodes(cfg, EvalSpec("center", "nominal", 5, seed=3))
    assert all(t.peg == cfg.cell.peg for t in nominal)
    # the same scenes for every condition and policy; other root seeds give other scenes
    assert [t.seed for t in nominal] == [t.seed for t in mass[:5]]
    assert {t.seed for t in plan_episodes(cfg, EvalSpec("random", "nominal", 5, seed=4))} \
        .isdisjoint(t.seed for t in nominal)


@pytest.mark.slow
def test_one_and_two_workers_give_identical_rows(cfg, run_dir, one_worker, tmp_path) -> None:
    two = evaluate_many(cfg, _jobs(run_dir, tmp_path), workers=2, progress=False)
    for a, b in zip(one_worker, two, strict=True):
        pd.testing.assert_frame_equal(a.drop(columns=VOLATILE), b.drop(columns=VOLATILE))
    greedy = one_worker[0]
    assert list(greedy["policy"]) == ["vgs", "vgs"] and list(greedy["index"]) == [0, 1]
    assert greedy["q_value"].notna().all() and (greedy["rotation"] >= 0).all()
    assert (tmp_path / "greedy" / "episodes.parquet").exists()
    assert (tmp_path / "greedy" / "episodes.csv").exists()
    assert json.loads((tmp_path / "random" / "summary.json").read_text())["episodes"] == 1


@pytest.mark.slow
def test_ray_backend_gives_the_local_rows(cfg, run_dir, one_worker, tmp_path) -> None:
    pytest.importorskip("ray", reason="the Ray extra is part of the dev install")
    ray_rows = evaluate_many(cfg, _jobs(run_dir, tmp_path), workers=2, backend="ray",
                             progress=False)
    for a, b in zip(one_worker, ray_rows, strict=True):
        pd.testing.assert_frame_equal(a.drop(columns=VOLATILE), b.drop(columns=VOLATILE))


@pytest.mark.slow
def test_an_episode_that_raises_stops_the_run(cfg, tmp_path) -> None:
    """A bug is not a result: the run stops naming the episode and the error, and writes no
    row for it (nor a table)."""
    with pytest.raises(EpisodeError, match=r"episode \d \(seed \d+\) raised RuntimeError: "
                                           "policy exploded"):
        evaluate(cfg, EvalSpec(f"{POLICIES}:raising", "nominal", 2, seed=1), tmp_path,
                 workers=2, progress=False)
    assert not (tmp_path / "journal.jsonl").read_text()
    assert not (tmp_path / "episodes.csv").exists()


@pytest.mark.slow
def test_a_lost_worker_is_retried(cfg, tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("VGS_TEST_MARKER", str(tmp_path / "marker"))
    jobs = [(EvalSpec(f"{POLICIES}:crash_once", "nominal", 1, seed=1), tmp_path / "once"),
            (EvalSpec(f"{POLICIES}:crash_always", "nominal", 1, seed=1), tmp_path / "always")]
    once, always = evaluate_many(cfg, jobs, workers=2, progress=False)
    assert (tmp_path / "marker").exists()  # the first attempt did die
    assert once["grasp_success"].iloc[0] and once["failure_reason"].iloc[0] != "worker_lost"
    assert always["failure_reason"].iloc[0] == "worker_lost"


def test_resume_skips_journaled_episodes(cfg, tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(episodepool, "EpisodeRunner", fakes.FakeRunner)  # no physics
    spec = EvalSpec("random", "nominal", 3, seed=1)
    evaluate(cfg, replace(spec, episodes=2), tmp_path, workers=1, progress=False)
    journal = tmp_path / "journal.jsonl"
    lines = journal.read_text().splitlines()
    journal.write_text("\n".join(lines[:1]) + "\n{\"index\": 1, \"cut")  # killed mid-write
    df = evaluate(cfg, spec, tmp_path, workers=1, progress=False)
    assert list(df["index"]) == [0, 1, 2]
    kept = [json.loads(line) for line in journal.read_text().splitlines()]
    assert [r["index"] for r in kept] == [0, 1, 2]  # the torn line is gone


def test_bad_input_is_a_config_error(cfg, tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(episodepool, "EpisodeRunner", fakes.FakeRunner)  # no physics
    with pytest.raises(ConfigError, match="policy"):
        evaluate(cfg, EvalSpec("no_such_policy", "nominal", 1), tmp_path, progress=False)
    with pytest.raises(ConfigError, match="condition"):
        EvalSpec("center", "heavy", 1)
    with pytest.raises(ConfigError, match="backend"):
        evaluate(cfg, EvalSpec("center", "nominal", 1), tmp_path, backend="slurm",
                 progress=False)
    with pytest.raises(ConfigError, match="workers"):
        evaluate(cfg, EvalSpec("center", "nominal", 1), tmp_path, workers=0, progress=False)
    evaluate(cfg, EvalSpec("random", "nominal", 1), tmp_path / "a", progress=False)
    with pytest.raises(ConfigError, match="another evaluation"):
        evaluate(cfg, EvalSpec("random", "mass", 1), tmp_path / "a", progress=False)


def test_heuristic_workers_start_without_torch() -> None:
    """A worker of the centre policy never imports torch (it would add seconds to each worker's
    start-up); a training run's policy does."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from vgs.config import profile\n"
        "from vgs.rollout.episodepool import EpisodeWorker\n"
        "cfg = profile('smoke')\n"
        "worker = EpisodeWorker(cfg)\n"
        "worker.policy('center')\n"
        "print('torch' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_network_worker_uses_one_torch_thread(cfg, run_dir: Path) -> None:
    from vgs.rollout.episodepool import EpisodeWorker

    threads = torch.get_num_threads()
    try:
        torch.set_num_threads(2)
        EpisodeWorker(cfg).policy(str(run_dir))
        assert torch.get_num_threads() == 1
    finally:
        torch.set_num_threads(threads)


def test_a_run_that_trained_on_is_another_policy(cfg, tmp_path: Path) -> None:
    """Rows of a checkpoint are not resumed with a later checkpoint of the same run."""
    import shutil

    run = tmp_path / "run"
    run.mkdir()
    agent = GraspAgent(cfg.network, cfg.agent, seed=5)
    (run / "run.json").write_text(json.dumps({"mode": "vgs", "config": to_dict(cfg)}))
    save_agent(run / "checkpoint.pt", agent, cfg, episode=3)
    out = tmp_path / "eval"
    spec = EvalSpec(str(run), "nominal", 1, seed=2)
    evaluate(cfg, spec, out, progress=False)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["policy_trained_episodes"] == 3
    evaluate(cfg, spec, out, progress=False)  # the same checkpoint: resumes
    # another network of the same length under the same path: its weights tell
    save_agent(run / "checkpoint.pt", GraspAgent(cfg.network, cfg.agent, seed=6), cfg,
               episode=3)
    with pytest.raises(ConfigError, match="policy_digest"):
        evaluate(cfg, spec, out, progress=False)
    save_agent(run / "checkpoint.pt", agent, cfg, episode=9)
    with pytest.raises(ConfigError, match="policy_trained_episodes"):
        evaluate(cfg, spec, out, progress=False)
    # folders whose digest was written with batch norm's counters (before 2026-12-07) resume
    legacy = policy_digest(str(run), load_policy(str(run), cfg), legacy=True)
    assert legacy != meta["policy_digest"]
    (out / "meta.json").write_text(json.dumps({**meta, "policy_digest": legacy,
                                               "policy_trained_episodes": 9}))
    evaluate(cfg, spec, out, progress=False)
    assert json.loads((out / "meta.json").read_text())["policy_digest"] == meta["policy_digest"]
    # folders written before the count was recorded resume as before
    del meta["policy_trained_episodes"]
    (out / "meta.json").write_text(json.dumps(meta))
    evaluate(cfg, spec, out, progress=False)
    shutil.rmtree(out)
