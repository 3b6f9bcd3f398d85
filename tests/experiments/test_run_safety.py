"""Runs you can trust: checkpoints that cannot run code, resumes that check what they resume,
one line for every user error, host-aware rows. Physics-free (:mod:`experiments.fakes`) except
where stated."""

from __future__ import annotations

import csv
import json
import pickle
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from vgs.cli import main
from vgs.config import to_dict
from vgs.runfolder.common import host, locked
from vgs.runfolder.journal import encode_row

from . import fakes

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def fake_physics(monkeypatch: pytest.MonkeyPatch):
    fakes.use_fake_physics(monkeypatch)


vgs, one_line = fakes.vgs, fakes.one_line


# -- checkpoints that cannot run code ------------------------------------------------------------


class Payload:
    """Unpickling it creates the marker file (a stand-in for any code an attacker wants run)."""

    def __init__(self, marker: str) -> None:
        self.marker = marker

    def __reduce__(self):
        return open, (self.marker, "w")


def _crafted(kind: str, marker: Path) -> bytes:
    if kind == "raw pickle":
        return pickle.dumps({"agent": Payload(str(marker))})
    if kind == "torch pickle":  # what torch.save writes; torch.load(weights_only=False) runs it
        import io

        buffer = io.BytesIO()
        torch.save({"agent": Payload(str(marker)), "episode": 3}, buffer)
        return buffer.getvalue()
    raise AssertionError(kind)


def _cli_config():
    from vgs.cli import build_parser, config_from_args

    return config_from_args(build_parser().parse_args(
        ["train", "--mode", "vgs", "--out", "x", *fakes.CLI_FLAGS]))


def _run_folder(folder: Path, mode: str, checkpoint_bytes: bytes, finished: bool) -> None:
    folder.mkdir(parents=True)
    (folder / "run.json").write_text(json.dumps({"mode": mode, "config": to_dict(_cli_config()),
                                                 "schedule_episodes": 6}))
    (folder / "checkpoint.pt").write_bytes(checkpoint_bytes)
    if finished:
        from vgs.runfolder.trainfolder import CSV_COLUMNS, episode_seed

        with (folder / "episodes.csv").open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
            writer.writeheader()
            for e in range(6):
                writer.writerow({"episode": e, "mode": mode, "seed": episode_seed(0, e)})
        (folder / "convergence.json").write_text("{}")


@pytest.mark.parametrize("kind", ["raw pickle", "torch pickle", "old vgs checkpoint"])
def test_a_crafted_checkpoint_is_refused_by_every_command_and_runs_nothing(
        kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    marker = tmp_path / "marker"
    if kind == "old vgs checkpoint":  # the format before 2026-12-02: pickled numpy arrays
        import io

        buffer = io.BytesIO()
        torch.save({"agent": {}, "replay": {"arrays": {"color": np.zeros((2, 4, 4, 3))}},
                    "rng_state": np.random.default_rng(0).bit_generator.state,
                    "episode": 6}, buffer)
        data = buffer.getvalue()
    else:
        data = _crafted(kind, marker)
        pickle.loads(data) if kind == "raw pickle" else torch.load(  # noqa: S301
            __import__("io").BytesIO(data), weights_only=False)
        assert marker.exists()  # the payload is live: loading it the old way runs it
        marker.unlink()

    run = tmp_path / "run"
    _run_folder(run, "vgs", data, finished=False)
    flags = fakes.CLI_FLAGS
    commands = {
        "train": ["train", "--mode", "vgs", "--out", str(run), *flags],
        "evaluate": ["evaluate", "--policy", str(run), "--workers", "1", "--episodes", "2",
                     "--out", str(tmp_path / "eval"), *flags],
        "heatmap": ["heatmap", str(run), "--out", str(tmp_path / "heat.png")],
        "status": ["status", str(run)],
    }
    repro = tmp_path / "repro"
    for mode in ("baseline", "vgs"):
        _run_folder(repro / "train" / f"{mode}_s0", mode, data, finished=True)
    commands["reproduce"] = ["reproduce", "--out", str(repro), "--workers", "1", "--stages",
                             "evaluate", *flags]
    commands["status reproduce"] = ["status", str(repro)]
    unfinished = tmp_path / "repro_train"
    for mode in ("baseline", "vgs"):
        _run_folder(unfinished / "train" / f"{mode}_s0", mode, data, finished=False)
    commands["reproduce train"] = ["reproduce", "--out", str(unfinished), "--workers", "1",
                                   "--stages", "train", *flags]
    for name, argv in commands.items():
        rc, lines = vgs(capsys, *argv)
        one_line(rc, lines, "checkpoint.pt")
        assert not marker.exists(), name
    assert not (tmp_path / "heat.png").exists() and not (tmp_path / "eval").exists()


def test_a_damaged_checkpoint_is_refused_and_status_does_not_say_done(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "run"
    rc, _ = vgs(capsys, "train", "--mode", "vgs", "--out", str(run), *fakes.CLI_FLAGS)
    assert rc == 0
    data = (run / "checkpoint.pt").read_bytes()
    (run / "checkpoint.pt").write_bytes(data[: len(data) - 1000])
    one_line(*vgs(capsys, "status", str(run)), "checkpoint.pt")
    one_line(*vgs(capsys, "evaluate", "--policy", str(run), "--out", str(tmp_path / "e"),
                  *fakes.CLI_FLAGS), "checkpoint.pt")


# -- resume checks what it resumes --------------------------------------------------------------


def _train_rows(run: Path) -> pd.DataFrame:
    return pd.read_csv(run / "episodes.csv").drop(columns=["wall_s"])


def test_train_extends_a_finished_run_and_refuses_another_seed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "run"
    rc, _ = vgs(capsys, "train", "--mode", "vgs", "--out", str(run), *fakes.CLI_FLAGS,
                "--episodes", "3")
    assert rc == 0
    first = _train_rows(run)
    assert len(first) == 3
    rc, _ = vgs(capsys, "train", "--mode", "vgs", "--out", str(run), *fakes.CLI_FLAGS,
                "--episodes", "6")
    assert rc == 0
    extended = _train_rows(run)
    assert list(extended["episode"]) == [0, 1, 2, 3, 4, 5]
    pd.testing.assert_frame_equal(extended.iloc[:3], first)
    meta = json.loads((run / "run.json").read_text())
    assert meta["config"]["train"]["episodes"] == 6 and meta["schedule_episodes"] == 3
    # the schedule is kept: episodes after the first request's end act at the final epsilon
    assert set(extended["epsilon"].iloc[3:]) == {fakes.tiny_config().agent.epsilon_end}
    for flag, value, field in (("--seed", "2", "seed"), ("--episodes", "4", "train.episodes"),
                               ("--peg-mass", "0.6", "cell.peg.mass"),
                               ("--profile", "quick", "name")):
        argv = ["train", "--mode", "vgs", "--out", str(run), *fakes.CLI_FLAGS, "--episodes",
                "6", flag, value]
        rc, lines = vgs(capsys, *argv)
        one_line(rc, lines, f"error: {field}:")
    one_line(*vgs(capsys, "train", "--mode", "baseline", "--out", str(run), *fakes.CLI_FLAGS),
             "mode")
    pd.testing.assert_frame_equal(_train_rows(run), extended)  # nothing was touched
    assert json.loads((run / "run.json").read_text()) == meta
    # a run resumed on another host says so
    assert meta["hosts"] == [host()]
    assert main(["status", str(run)]) == 0 and "hosts" not in capsys.readouterr().out
    meta["hosts"].insert(0, {"host_cpu": "Other CPU 9000", "mujoco_version": "3.0.0"})
    (run / "run.json").write_text(json.dumps(meta))
    assert main(["status", str(run)]) == 0
    assert "trained on 2 hosts (Other CPU 9000, MuJoCo 3.0.0; " in capsys.readouterr().out


def test_bad_values_are_refused_before_anything_is_written(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "new"
    cases = [
        (["train", "--mode", "vgs", "--set", "train.episodes=2.5"], "train.episodes"),
        (["train", "--mode", "vgs", "--seed", "-1"], "--seed"),
        (["train", "--mode", "vgs", "--set", "seed=abc"], "seed"),
        (["train", "--mode", "vgs", "--set", "seed=-3"], "seed"),
        (["train", "--mode", "vgs", "--set", "cell.peg.mass=True"], "cell.peg.mass"),
        (["train", "--mode", "vgs", "--set", "cell.hole.randomize=1"], "cell.hole.randomize"),
        (["evaluate", "--policy", "center", "--seed", "-1"], "--seed"),
        (["evaluate", "--policy", "center", "--workers", "0"], "workers"),
        (["reproduce", "--set", "reproduce.train_seeds=(-1,)"], "reproduce.train_seeds"),
        (["reproduce", "--set", "reproduce.eval_seed=True"], "reproduce.eval_seed"),
        (["sweep", "--seed", "-2"], "--seed"),
        (["reproduce", "--stages", "train,fly"], "stages"),
    ]
    for argv, field in cases:
        one_line(*vgs(capsys, *argv, "--out", str(out), "--profile", "smoke"), field)
        assert not out.exists(), argv
    a_file = tmp_path / "file"
    a_file.write_text("x")
    for argv in (["train", "--mode", "vgs"], ["evaluate", "--policy", "center"],
                 ["reproduce"], ["sweep", "--trials", "1"]):
        one_line(*vgs(capsys, *argv, "--out", str(a_file), *fakes.CONFIG_FLAGS), str(a_file))
    one_line(*vgs(capsys, "train", "--mode", "vgs", "--out", str(a_file / "sub"),
                  *fakes.CLI_FLAGS), str(a_file))


def _eval(capsys, out: Path, *extra: str) -> tuple[int, list[str]]:
    return vgs(capsys, "evaluate", "--policy", "center", "--episodes", "4", "--workers", "1",
               "--out", str(out), *fakes.CLI_FLAGS, *extra)


def test_a_relabelled_journal_is_refused(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    """The issue's repro: meta.json lost, a nominal journal resumed as a mass evaluation with
    another seed (and each change on its own)."""
    out = tmp_path / "eval"
    assert _eval(capsys, out)[0] == 0
    table = pd.read_parquet(out / "episodes.parquet")
    (out / "meta.json").unlink()
    for extra in (["--condition", "mass", "--seed", "5"], ["--condition", "mass"],
                  ["--seed", "5"], ["--condition", "length"]):
        one_line(*_eval(capsys, out, *extra), "journal.jsonl:1", "not this evaluation's")
    one_line(*_eval(capsys, out, "--episodes", "2"), "journal.jsonl:3", "outside")
    assert _eval(capsys, out)[0] == 0  # the original request still resumes
    pd.testing.assert_frame_equal(pd.read_parquet(out / "episodes.parquet").drop(
        columns="wall_s"), table.drop(columns="wall_s"))
    # with meta.json in place the field is named
    one_line(*_eval(capsys, out, "--condition", "mass"), "condition")
    one_line(*_eval(capsys, out, "--seed", "5"), "seed")
    one_line(*_eval(capsys, out, "--peg-mass", "0.6"), "cell.peg.mass")
    one_line(*_eval(capsys, out, "--episodes", "3"), "episodes")
    assert _eval(capsys, out, "--episodes", "6")[0] == 0  # more tests: extends
    assert len(pd.read_parquet(out / "episodes.parquet")) == 6


def test_unreadable_journals_and_metadata_are_refused_naming_file_and_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ref = tmp_path / "ref"
    assert _eval(capsys, ref)[0] == 0
    lines = (ref / "journal.jsonl").read_bytes().splitlines(keepends=True)
    cases = {
        "duplicate": (b"".join(lines[:3]) + lines[1] + lines[3], "journal.jsonl:4", "repeats"),
        "not utf-8": (lines[0] + b"\xff\xfe\n" + b"".join(lines[1:]), "journal.jsonl:2",
                      "UTF-8"),
        "not a row": (lines[0] + encode_row({"hello": 1}).encode() + b"".join(lines[1:]),
                      "journal.jsonl:2", "not an episode row"),
        "no checksum": (lines[0] + b'{"index": 1}\n' + b"".join(lines[2:]), "journal.jsonl:2",
                        "without its crc32"),
        "not json": (lines[0] + b"hello\n" + b"".join(lines[1:]), "journal.jsonl:2", "JSON"),
    }
    for name, (data, where, words) in cases.items():
        out = tmp_path / name.replace(" ", "_")
        shutil.copytree(ref, out)
        (out / "journal.jsonl").write_bytes(data)
        one_line(*_eval(capsys, out), where, words)
        one_line(*vgs(capsys, "status", str(out)), where)
    out = tmp_path / "empty_meta"
    shutil.copytree(ref, out)
    (out / "meta.json").write_text("")
    one_line(*_eval(capsys, out), "meta.json", "empty")
    # a line cut by a kill is dropped and its episode runs again
    out = tmp_path / "cut"
    shutil.copytree(ref, out)
    (out / "journal.jsonl").write_bytes(b"".join(lines[:3]) + lines[3][:40])
    assert _eval(capsys, out)[0] == 0
    pd.testing.assert_frame_equal(
        pd.read_parquet(out / "episodes.parquet").drop(columns="wall_s"),
        pd.read_parquet(ref / "episodes.parquet").drop(columns="wall_s"))


def test_a_second_run_in_a_locked_folder_is_refused(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "eval"
    with locked(out):
        one_line(*_eval(capsys, out), "in use by another vgs process")
        one_line(*vgs(capsys, "train", "--mode", "vgs", "--out", str(out), *fakes.CLI_FLAGS),
                 "in use")
        one_line(*vgs(capsys, "reproduce", "--out", str(out), *fakes.CLI_FLAGS), "in use")
    assert _eval(capsys, out)[0] == 0  # released


def test_ctrl_c_is_one_line_and_the_run_resumes(tmp_path: Path, capsys,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    ref, out = tmp_path / "ref", tmp_path / "out"
    assert _eval(capsys, ref)[0] == 0
    calls = {"n": 0}
    original = fakes.FakeRunner.run

    def interrupted(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return original(self, *args, **kwargs)

    monkeypatch.setattr(fakes.FakeRunner, "run", interrupted)
    capsys.readouterr()
    assert main(["evaluate", "--policy", "center", "--episodes", "4", "--workers", "1",
                 "--out", str(out), *fakes.CLI_FLAGS]) == 130
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("eval ")]
    assert err == ["vgs: interrupted; run the same command again to resume (finished episodes "
                   "are kept)"]
    monkeypatch.setattr(fakes.FakeRunner, "run", original)
    assert _eval(capsys, out)[0] == 0
    pd.testing.assert_frame_equal(
        pd.read_parquet(out / "episodes.parquet").drop(columns="wall_s"),
        pd.read_parquet(ref / "episodes.parquet").drop(columns="wall_s"))


# -- host-aware rows -----------------------------------------------------------------------------


def test_rows_record_the_host_and_mixed_hosts_are_reported(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from vgs.analysis.report import hosts_note

    out = tmp_path / "eval"
    assert _eval(capsys, out)[0] == 0
    table = pd.read_parquet(out / "episodes.parquet")
    assert set(table["host_cpu"]) == {host()["host_cpu"]} and host()["host_cpu"]
    import mujoco

    assert set(table["mujoco_version"]) == {mujoco.__version__}
    assert "one host" in hosts_note(table)
    rc, _ = vgs(capsys, "status", str(out))
    assert "hosts" not in capsys.readouterr().out
    # the last two episodes ran elsewhere (a journal resumed on another machine)
    rows = [json.loads(line) for line in (out / "journal.jsonl").read_text().splitlines()]
    for row in rows:
        row.pop("crc32")
    for row in rows[2:]:
        row["host_cpu"] = "Other CPU 9000"
    (out / "journal.jsonl").write_text("".join(encode_row(r) for r in rows))
    (out / "summary.json").unlink()
    assert _eval(capsys, out)[0] == 0
    rc = main(["status", str(out)])
    text = capsys.readouterr().out
    assert rc == 0 and "episodes from 2 hosts" in text and "Other CPU 9000" in text
    mixed = pd.read_parquet(out / "episodes.parquet")
    assert "come from several hosts" in hosts_note(mixed) and "center/nominal" in hosts_note(
        mixed)
    assert hosts_note(mixed.drop(columns=["host_cpu", "mujoco_version"])) == ""


def test_published_results_load_and_their_reports_rebuild(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A published result set (docs/results, made before ``across_mm`` was a column) still
    reads, reports and shows its status; real files."""
    src = REPO / "docs" / "results" / "paper_light_s0"
    out = tmp_path / "published"
    shutil.copytree(src, out)
    capsys.readouterr()
    assert main(["report", str(out)]) == 0
    report = (out / "report.md").read_text()
    assert "| nominal |" in report and "All test episodes ran on one host" in report
    assert main(["status", str(out)]) == 0
    assert "report:" in capsys.readouterr().out


def test_publish_copies_regular_files_never_a_links_target(tmp_path: Path) -> None:
    """``vgs report --publish`` copies the results, not what a symlink in the folder points to
    (issue 41)."""
    from vgs.tools.publish import publish

    out, dest = tmp_path / "repro", tmp_path / "pub"
    (out / "sweep").mkdir(parents=True)
    (out / "report.md").write_text("# report\n")
    (out / "sweep" / "sweep.csv").write_text("offset_mm\n0.0\n")
    secret = tmp_path / "secret.txt"
    secret.write_text("not a result")
    (out / "sweep" / "summary.json").symlink_to(secret)
    copied = publish(out, dest)
    assert sorted(p.relative_to(dest).as_posix() for p in copied) == ["report.md",
                                                                       "sweep/sweep.csv"]
    assert not (dest / "sweep" / "summary.json").exists()
