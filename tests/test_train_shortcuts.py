"""Training's two shortcuts (``train.assemble_baseline = False``, ``train.stop_at_threshold``)
end episodes once their reward is known and change no reward, update or network."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest

from vgs.assembly.episode import EpisodeRunner, center_policy
from vgs.config import ExperimentConfig, override, profile
from vgs.experiments import train as train_mod

LEARNING = ("episode", "seed", "explored", "rotation", "row", "col", "q_value", "grasp_success",
            "grasp_offset_mm", "r_grasp", "r_assembly", "reward", "loss", "delta_q")


@pytest.fixture(scope="module")
def runner() -> EpisodeRunner:
    return EpisodeRunner(profile("smoke"))


@pytest.mark.slow
def test_a_time_limit_stops_only_a_slower_assembly(runner: EpisodeRunner) -> None:
    full, _, _ = runner.run(3, center_policy())
    assert full.success
    row = json.dumps(full.to_row(), sort_keys=True)
    # Above the assembly's time the limit changes nothing, to the digit.
    later, _, _ = runner.run(3, center_policy(), time_limit=full.assembly_time + 0.5)
    assert json.dumps(later.to_row(), sort_keys=True) == row
    # Below it the assembly stops soon after the limit, as a failure that names its phase.
    limit = 0.6 * full.assembly_time
    cut, _, _ = runner.run(3, center_policy(), time_limit=limit)
    assert not cut.success and cut.failure_reason.startswith("cutoff:")
    assert limit < cut.assembly_time < full.assembly_time
    assert cut.grasp_offset == full.grasp_offset


@pytest.mark.slow
def test_without_assembly_the_episode_ends_holding_the_peg(runner: EpisodeRunner) -> None:
    full, _, _ = runner.run(3, center_policy())
    held, robot, _ = runner.run(3, center_policy(), assemble=False)
    assert held.grasp_success and not held.success and held.failure_reason == "no_assembly"
    assert held.grasp_offset == full.grasp_offset and math.isnan(held.assembly_time)
    assert robot.time < 10.0  # the grasp and the lift only


def _config(shortcuts: bool) -> ExperimentConfig:
    cfg = profile("smoke")
    cfg = override(cfg, "cell.camera.size", 64)
    cfg = override(cfg, "cell.camera.pixel_size", 0.007)
    cfg = override(cfg, "train.episodes", 4)
    cfg = override(cfg, "agent.random_episodes", 1)
    cfg = override(cfg, "reward.threshold_s", 20.0)  # below most assemblies: they are cut
    cfg = override(cfg, "train.assemble_baseline", not shortcuts)
    return override(cfg, "train.stop_at_threshold", shortcuts)


def _rows(run: Path) -> list[dict[str, str]]:
    with (run / "episodes.csv").open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["vgs", "baseline"])
def test_the_shortcuts_change_no_reward_and_no_update(tmp_path: Path, mode: str) -> None:
    whole = _rows(train_mod.train(_config(False), mode, tmp_path / "whole", progress=False))
    short = _rows(train_mod.train(_config(True), mode, tmp_path / "short", progress=False))
    assert [{k: r[k] for k in LEARNING} for r in short] == \
        [{k: r[k] for k in LEARNING} for r in whole]
    reasons = {r["failure_reason"].split(":")[0] for r in short if r["grasp_success"] == "True"}
    if mode == "baseline":
        assert reasons == {"no_assembly"}
    else:  # with the threshold given, every assembly slower than 20 s is cut
        assert "cutoff" in reasons and "no_assembly" not in reasons
        for r, w in zip(short, whole, strict=True):
            if r["failure_reason"].startswith("cutoff"):
                assert float(r["assembly_time_s"]) > 20.0
                assert w["assembly_success"] == "False" or float(w["assembly_time_s"]) > 20.0
