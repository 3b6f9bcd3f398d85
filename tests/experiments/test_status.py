"""``vgs status``: progress read from the files of half-finished runs (no physics, no torch)."""

from __future__ import annotations

import csv
import json
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from vgs import checkpoint
from vgs.config import profile, to_dict
from vgs.errors import ConfigError
from vgs.runfolder.journal import encode_row
from vgs.runfolder.layout import eval_jobs, train_runs
from vgs.runfolder.status import eval_progress, folder_status, format_status, train_progress

COLUMNS = ("episode", "mode", "seed", "grasp_success", "assembly_success", "assembly_time_s",
           "wall_s")


def _config():
    cfg = profile("smoke")
    return replace(cfg, train=replace(cfg.train, episodes=10, checkpoint_every=4),
                   agent=replace(cfg.agent, random_episodes=8),
                   eval=replace(cfg.eval, episodes=5),
                   reproduce=replace(cfg.reproduce, conditions=("nominal",), sweep_offsets=0))


def _eval_meta(episodes: int) -> str:
    """An evaluation's meta.json (vgs.runfolder.schema)."""
    return json.dumps({"policy": "center", "condition": "nominal", "episodes": episodes,
                       "seed": 0, "config": to_dict(_config())})


def _train_run(folder: Path, cfg, walls: list[float], converged: bool = False) -> None:
    folder.mkdir(parents=True)
    (folder / "run.json").write_text(json.dumps({"mode": "vgs", "config": to_dict(cfg)}))
    with (folder / "episodes.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        writer.writeheader()
        for i, wall in enumerate(walls):
            writer.writerow({"episode": i, "mode": "vgs", "seed": i, "grasp_success": 1,
                             "assembly_success": i % 2, "assembly_time_s": 20.0,
                             "wall_s": wall})
    # checkpoint_every = 4; a finished run checkpoints its last episode
    at = len(walls) if converged else len(walls) - len(walls) % 4
    checkpoint.save(folder / "checkpoint.pt", {}, {"episode": at})
    if converged:
        (folder / "convergence.json").write_text("{}")


def test_training_run_half_way(tmp_path: Path) -> None:
    cfg = _config()
    _train_run(tmp_path / "run", cfg, [2.0] * 6)
    p = train_progress(tmp_path / "run")
    assert (p.done, p.total, p.finished) == (6, 10, False)
    assert p.seconds_per_episode == pytest.approx(2.0)
    assert p.remaining_h == pytest.approx(4 * 2.0 / 3600)
    assert "resumes at episode 4" in p.note and "random exploration until episode 8" in p.note
    assert "assembly 0.50" in p.note


def test_finished_training_run(tmp_path: Path) -> None:
    cfg = _config()
    _train_run(tmp_path / "run", cfg, [1.0] * 10, converged=True)
    p = train_progress(tmp_path / "run")
    assert p.finished and p.remaining_h is None and "done" in p.line()


def test_evaluation_with_a_torn_journal_line(tmp_path: Path) -> None:
    out = tmp_path / "eval"
    out.mkdir()
    (out / "meta.json").write_text(_eval_meta(5))
    rows = [{"index": i, "success": i != 1, "wall_s": 3.0} for i in range(3)]
    (out / "journal.jsonl").write_text("".join(encode_row(r) for r in rows) + '{"ind')
    p = eval_progress(out)
    assert (p.done, p.total, p.finished) == (3, 5, False)
    assert p.note == "assembled 2/3" and p.seconds_per_episode == pytest.approx(3.0)


def test_evaluation_with_all_episodes_in_but_no_tables_yet(tmp_path: Path) -> None:
    out = tmp_path / "eval"
    out.mkdir()
    (out / "meta.json").write_text(_eval_meta(2))
    (out / "journal.jsonl").write_text(
        "".join(encode_row({"index": i, "success": True, "wall_s": 1.0}) for i in (0, 1)))
    p = eval_progress(out)
    assert (p.done, p.finished) == (2, False)
    assert "all episodes in, tables written when the evaluation ends" in p.note
    (out / "summary.json").write_text("{}")
    p = eval_progress(out)
    assert p.finished and p.note == "assembled 2/2"


def test_reproduction_folder(tmp_path: Path) -> None:
    cfg = _config()
    out = tmp_path / "repro"
    out.mkdir()
    (out / "reproduce.json").write_text(json.dumps(
        {"profile": "smoke", "config": to_dict(cfg), "git_revision": "abcdef0123",
         "stage_wall_s": {"train": 7200.0}}))
    runs = train_runs(cfg, out)
    _train_run(runs[0].folder, cfg, [1.0] * 10, converged=True)
    _train_run(runs[1].folder, cfg, [1.0] * 3)
    done_job = eval_jobs(cfg, out)[-1]  # the centre heuristic
    done_job.folder.mkdir(parents=True)
    (done_job.folder / "meta.json").write_text(_eval_meta(5))
    (done_job.folder / "journal.jsonl").write_text(
        "".join(encode_row({"index": i, "success": True, "wall_s": 1.0})
                for i in range(5)))
    (done_job.folder / "summary.json").write_text("{}")
    sections = dict(folder_status(out))
    assert [p.finished for p in sections["train"]] == [True, False]
    assert [p.done for p in sections["evaluate"]] == [0, 0, 5]
    assert [p.finished for p in sections["evaluate"]] == [False, False, True]
    assert [p.total for p in sections["evaluate"]] == [5, 5, 5]
    text = format_status(out)
    assert "smoke profile, source abcdef0123" in text and "train 2.00 h" in text
    assert "train (1/2 done)" in text and "evaluate (1/3 done)" in text
    assert "not started" in text and "report: not written yet" in text
    meta = json.loads((out / "reproduce.json").read_text())
    for revision in ("installed package", "unknown"):  # whole, not cut to a hash's length
        (out / "reproduce.json").write_text(json.dumps({**meta, "git_revision": revision}))
        assert f"smoke profile, source {revision}\n" in format_status(out)


def test_reproduction_with_a_training_run_not_started(tmp_path: Path) -> None:
    """A carried reproduction whose second training run has not begun (its folder absent)."""
    cfg = _config()
    out = tmp_path / "repro"
    out.mkdir()
    (out / "reproduce.json").write_text(json.dumps({"profile": "smoke", "config": to_dict(cfg)}))
    runs = train_runs(cfg, out)
    _train_run(runs[0].folder, cfg, [1.0] * 10, converged=True)
    train = dict(folder_status(out))["train"]
    assert [(p.done, p.total, p.finished) for p in train] == [(10, 10, True), (0, 10, False)]
    assert "0/10    not started" in format_status(out)


def test_not_a_run_folder(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="is not a reproduction"):
        folder_status(tmp_path)
    with pytest.raises(ConfigError, match="is not a folder"):
        folder_status(tmp_path / "missing")


def test_status_does_not_import_torch(tmp_path: Path) -> None:
    """Instant while a run works: ``vgs status`` never loads torch or a checkpoint."""
    import subprocess

    (tmp_path / "meta.json").write_text(_eval_meta(5))
    code = ("import sys; from vgs.cli import main; "
            f"assert main(['status', {str(tmp_path)!r}]) == 0; "
            "assert 'torch' not in sys.modules")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "0/5" in proc.stdout


def test_engine_note_names_another_mujoco_and_is_silent_for_the_installed_one() -> None:
    from vgs.runfolder.common import engine_note, host

    installed = host()["mujoco_version"]
    assert engine_note([{"mujoco_version": installed}, {"host_cpu": "x"}]) == ""
    note = engine_note([{"mujoco_version": installed}, {"mujoco_version": "3.3.0"}])
    assert "MuJoCo 3.3.0" in note and f"installed {installed}" in note
    assert "\n" not in note
