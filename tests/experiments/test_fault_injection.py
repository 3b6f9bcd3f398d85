"""Fault injection: training and evaluation killed at random points (SIGKILL from outside),
every file a run keeps damaged in several ways, then resumed. After each resume the table must
be the one an uninterrupted run writes, or the command must refuse with one line (exit 2).

The physics is :class:`experiments.fakes.FakeRunner` (milliseconds per episode), so the test
exercises journals, checkpoints, locks and refusals, not the cell; it runs in the normal suite
in well under a minute.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import random
import shutil
import signal
import time
from pathlib import Path

import pandas as pd
import pytest

from vgs.cli import main
from vgs.experiments.evaluate import EvalSpec, evaluate
from vgs.experiments.train import train

from . import fakes

VOLATILE = ["wall_s"]
EVAL_SEED = 7
TRIALS = 4  # kills of each kind


def train_table(run: Path) -> pd.DataFrame:
    return pd.read_csv(run / "episodes.csv").drop(columns=VOLATILE)


def eval_table(out: Path) -> pd.DataFrame:
    return pd.read_parquet(out / "episodes.parquet").drop(columns=VOLATILE)


def _train(out: Path) -> None:
    train(fakes.tiny_config(), "vgs", out, progress=False, threads=1)


def _evaluate(out: Path) -> None:
    evaluate(fakes.tiny_config(), EvalSpec("random", "mass", 8, seed=EVAL_SEED), out,
             workers=1, progress=False)


def _child(kind: str, out: str, delay: float) -> None:
    """Body of a process that is killed from outside."""
    fakes.install(delay)
    (_train if kind == "train" else _evaluate)(Path(out))


@pytest.fixture(scope="module")
def fake_physics():
    from vgs.experiments import train as train_mod
    from vgs.rollout import episodepool

    saved = train_mod.EpisodeRunner, episodepool.EpisodeRunner
    fakes.install()
    yield
    train_mod.EpisodeRunner, episodepool.EpisodeRunner = saved


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory, fake_physics) -> dict[str, Path]:
    """Uninterrupted runs: a training run and an evaluation."""
    root = tmp_path_factory.mktemp("reference")
    _train(root / "train")
    _evaluate(root / "eval")
    return {"train": root / "train", "eval": root / "eval"}


def _tables_equal(kind: str, out: Path, ref: Path) -> None:
    if kind == "train":
        pd.testing.assert_frame_equal(train_table(out), train_table(ref))
    else:
        pd.testing.assert_frame_equal(eval_table(out), eval_table(ref))


def test_killed_runs_resume_to_the_uninterrupted_table(tmp_path: Path, reference) -> None:
    """SIGKILL at a random moment (mid-episode, mid-write, mid-checkpoint ...), then resume."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["experiments.fakes", "vgs.experiments.train",
                                "vgs.experiments.evaluate", "torch.utils.tensorboard"])
    rnd = random.Random(20261202)
    # How long each whole run takes in a child here (train: 6 episodes; evaluate: 8): the kills
    # are drawn over that span. (The first child also starts the fork server.)
    spans = {}
    for kind in ("train", "eval", "train"):
        proc = ctx.Process(target=_child, args=(kind, str(tmp_path / f"calibrate_{kind}"), 0.03))
        t0 = time.perf_counter()
        proc.start()
        proc.join(60)
        assert proc.exitcode == 0
        spans[kind] = time.perf_counter() - t0
        shutil.rmtree(tmp_path / f"calibrate_{kind}")
    killed = partial = 0
    for trial in range(TRIALS):
        for kind in ("train", "eval"):
            out = tmp_path / f"{kind}{trial}"
            table = out / ("episodes.csv" if kind == "train" else "journal.jsonl")
            proc = ctx.Process(target=_child, args=(kind, str(out), 0.03))
            proc.start()
            if trial % 2:
                # Half the kills wait for the first row, so that some land inside the episodes
                # however slow a loaded host makes the start (a random time alone can miss).
                deadline = time.perf_counter() + 3 * spans[kind]
                while (proc.is_alive() and time.perf_counter() < deadline and not (
                        table.exists() and len(table.read_bytes().splitlines()) > 1)):
                    time.sleep(0.005)
                time.sleep(rnd.uniform(0.0, 0.2 * spans[kind]))
            else:
                time.sleep(rnd.uniform(0.02, 0.95 * spans[kind]))
            if proc.is_alive():
                os.kill(proc.pid, signal.SIGKILL)
                killed += 1
            proc.join(30)
            assert proc.exitcode is not None
            if table.exists() and 0 < len(table.read_bytes().splitlines()) - (
                    kind == "train") < (6 if kind == "train" else 8):
                partial += 1  # killed half-way through the episodes
            (_train if kind == "train" else _evaluate)(out)  # resume
            _tables_equal(kind, out, reference[kind])
    assert killed >= TRIALS and partial >= 2, (killed, partial)  # kills landed inside runs


def test_kill_inside_writes_resumes_to_the_uninterrupted_table(tmp_path: Path,
                                                              reference) -> None:
    """The states a kill can leave inside a write: a journal line or table row cut at any byte,
    temporary files of an atomic write left behind."""
    rnd = random.Random(5)
    journal = (reference["eval"] / "journal.jsonl").read_bytes()
    for trial in range(TRIALS):
        out = tmp_path / f"eval{trial}"
        shutil.copytree(reference["eval"], out)
        for name in ("episodes.parquet", "episodes.csv", "summary.json"):
            (out / name).unlink()
        cut = rnd.randrange(1, len(journal))
        (out / "journal.jsonl").write_bytes(journal[:cut])
        (out / ".meta.json.tmp").write_bytes(b'{"half')
        (out / ".episodes.parquet.tmp").write_bytes(b"PAR1\x00")
        _evaluate(out)
        _tables_equal("eval", out, reference["eval"])
    for trial in range(2):
        out = tmp_path / f"train{trial}"
        shutil.copytree(reference["train"], out)
        (out / ".checkpoint.pt.tmp").write_bytes(os.urandom(100))
        with (out / "episodes.csv").open("ab") as fh:  # a row cut after the last checkpoint
            fh.write(b"6,vgs,123" if trial else b"6")
        _train(out)
        _tables_equal("train", out, reference["train"])


CORRUPTIONS = ("delete", "empty", "truncate", "garbage", "flip", "duplicate_line")


def _corrupt(path: Path, how: str, rnd: random.Random) -> None:
    data = path.read_bytes()
    if how == "delete":
        path.unlink()
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "truncate":
        path.write_bytes(data[:len(data) // 2])
    elif how == "garbage":
        path.write_bytes(b"\xff\xfe\x00garbage\x80\n" + data[: len(data) // 3])
    elif how == "flip":
        if data:
            i = rnd.randrange(len(data))
            path.write_bytes(data[:i] + bytes([data[i] ^ 0x5A]) + data[i + 1:])
    elif how == "duplicate_line":
        lines = data.splitlines(keepends=True)
        path.write_bytes(data + (lines[-1] if lines else b"x\n"))


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file())


def _resume_cli(kind: str, out: Path, capsys: pytest.CaptureFixture[str]) -> int:
    if kind == "train":
        argv = ["train", "--mode", "vgs", "--episodes", "6", "--out", str(out), *fakes.CLI_FLAGS]
    else:
        argv = ["evaluate", "--policy", "random", "--condition", "mass", "--episodes", "8",
                "--seed", str(EVAL_SEED), "--workers", "1", "--out", str(out), *fakes.CLI_FLAGS]
    capsys.readouterr()
    return main(argv)


@pytest.mark.parametrize("kind", ["train", "eval"])
def test_every_damaged_file_resumes_identically_or_is_refused_in_one_line(
        kind: str, tmp_path: Path, reference, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(os, "cpu_count", lambda: 1)  # one torch thread, as the reference
    rnd = random.Random(kind)
    ref = reference[kind]
    outcomes = {"identical": 0, "refused": 0}
    names = [p.relative_to(ref) for p in _files(ref)]
    assert len(names) >= 5
    for name in names:
        for how in CORRUPTIONS:
            out = tmp_path / f"{str(name).replace('/', '_')}-{how}"
            shutil.copytree(ref, out)
            _corrupt(out / name, how, rnd)
            rc = _resume_cli(kind, out, capsys)
            err = capsys.readouterr().err
            if rc == 0:
                _tables_equal(kind, out, ref)
                outcomes["identical"] += 1
            else:
                lines = [line for line in err.splitlines() if not line.startswith(
                    ("train vgs", "eval "))]  # progress lines of unattended runs
                assert rc == 2, (name, how, err)
                assert len(lines) == 1 and lines[0].startswith("vgs: error: "), (name, how, err)
                assert "Traceback" not in err
                outcomes["refused"] += 1
            shutil.rmtree(out)
    # Damage to the files a resume relies on is refused; the rest is rewritten.
    assert outcomes["refused"] >= 8 and outcomes["identical"] >= 8, outcomes


# -- hostile files and signals (issue 41) -------------------------------------------------------

HOSTILE = ("cut", "garbage", "deep_nesting", "symlink_out", "device", "fifo", "oversized")


def _hostile(path: Path, how: str, outside: Path) -> None:
    """Damage ``path`` the way ``how`` says; ``outside`` is a folder outside the run."""
    data = path.read_bytes()
    if how == "cut":
        path.write_bytes(data[:max(1, len(data) // 3)])
    elif how == "garbage":
        path.write_bytes(os.urandom(64) + data[len(data) // 2:])
    elif how == "deep_nesting":  # as a whole file and as a journal's line
        path.write_bytes(b"[" * 50_000 + b"]" * 50_000 + b"\n" + data)
    elif how == "symlink_out":  # the same bytes, but outside the folder
        copy = outside / f"{path.name}.outside"
        copy.write_bytes(data)
        path.unlink()
        path.symlink_to(copy)
    elif how == "device":
        path.unlink()
        path.symlink_to("/dev/zero")
    elif how == "fifo":
        path.unlink()
        os.mkfifo(path)
    elif how == "oversized":  # sparse: 9 GiB that nothing may read whole
        with path.open("r+b") as fh:
            fh.truncate(9 << 30)


def _readers(kind: str, out: Path, scratch: Path) -> list[list[str]]:
    """Every command that reads a folder of ``kind``."""
    if kind == "train":
        return [["train", "--mode", "vgs", "--episodes", "6", "--out", str(out),
                 *fakes.CLI_FLAGS], ["status", str(out)],
                ["export-policy", str(out), "--out", str(scratch / "policy")],
                ["evaluate", "--policy", str(out), "--episodes", "1", "--workers", "1",
                 "--out", str(scratch / "eval"), *fakes.CLI_FLAGS]]
    if kind == "eval":
        return [["evaluate", "--policy", "random", "--condition", "mass", "--episodes", "8",
                 "--seed", str(EVAL_SEED), "--workers", "1", "--out", str(out),
                 *fakes.CLI_FLAGS], ["status", str(out)]]
    return [["sweep", "--offsets-mm=0,5", "--trials", "2", "--workers", "1", "--out", str(out),
             *fakes.CLI_FLAGS]]


@pytest.fixture(scope="module")
def sweep_reference(tmp_path_factory: pytest.TempPathFactory, fake_physics) -> Path:
    from vgs.experiments import sweep as sweep_mod

    saved = sweep_mod.EpisodeRunner
    sweep_mod.EpisodeRunner = fakes.FakeRunner  # type: ignore[misc]
    out = tmp_path_factory.mktemp("sweep") / "sweep"
    assert main(["sweep", "--offsets-mm=0,5", "--trials", "2", "--workers", "1", "--out",
                 str(out), *fakes.CLI_FLAGS]) == 0
    yield out
    sweep_mod.EpisodeRunner = saved


def _alarm(signum: int, frame: object) -> None:
    raise TimeoutError("a command hung on a hostile file")


@pytest.mark.parametrize("kind", ["train", "eval", "sweep"])
def test_hostile_files_for_every_reader(kind: str, tmp_path: Path, reference, sweep_reference,
                                        capsys: pytest.CaptureFixture[str],
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """Every file a run keeps, times every kind of damage, for every command that reads it:
    the command finishes with the uninterrupted table or refuses in one line (exit 2); it never
    hangs (FIFO), reads without bound (device, oversized), follows a link out of the folder or
    writes through it, nor ends in a traceback."""
    from vgs.experiments import sweep as sweep_mod

    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    monkeypatch.setattr(sweep_mod, "EpisodeRunner", fakes.FakeRunner)
    ref = sweep_reference if kind == "sweep" else reference[kind]
    names = [p.relative_to(ref) for p in _files(ref)
             if "tensorboard" not in p.parts and p.name != ".lock"]
    old = signal.signal(signal.SIGALRM, _alarm)
    refused = 0
    try:
        for name in names:
            for how in HOSTILE:
                for i, argv in enumerate(_readers(kind, tmp_path / "run", tmp_path / "x")):
                    for folder in ("run", "x", "outside"):
                        shutil.rmtree(tmp_path / folder, ignore_errors=True)
                    (tmp_path / "outside").mkdir()
                    shutil.copytree(ref, tmp_path / "run")
                    _hostile(tmp_path / "run" / name, how, tmp_path / "outside")
                    before = {p.name: p.read_bytes() for p in (tmp_path / "outside").iterdir()}
                    signal.alarm(30)
                    try:
                        rc, lines = fakes.vgs(capsys, *argv)
                    finally:
                        signal.alarm(0)
                    what = (str(name), how, argv[0], lines)
                    assert rc in (0, 2), what
                    if rc == 2:
                        assert len(lines) == 1 and lines[0].startswith("vgs: error: "), what
                        refused += 1
                    elif i == 0 and kind != "sweep":
                        _tables_equal(kind, tmp_path / "run", ref)
                    after = {p.name: p.read_bytes() for p in (tmp_path / "outside").iterdir()}
                    assert after == before, what  # nothing written through a link
    finally:
        signal.signal(signal.SIGALRM, old)
    assert refused >= 2 * len(HOSTILE), refused  # at least the metadata and the journal


def test_sigterm_stops_workers_and_resumes(tmp_path: Path, reference) -> None:
    """SIGTERM to ``vgs evaluate --workers 2`` ends in one line and exit code 143, its worker
    processes stopped; run again, the evaluation ends with the uninterrupted table."""
    import subprocess
    import sys

    out = tmp_path / "eval"
    argv = ["evaluate", "--policy", "random", "--condition", "mass", "--episodes", "8", "--seed",
            str(EVAL_SEED), "--workers", "2", "--out", str(out), *fakes.CLI_FLAGS]
    code = f"from experiments import fakes; fakes.run_cli({argv!r}, 0.0)"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, stderr=subprocess.PIPE,
                            text=True)
    children: set[int] = set()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(children) < 2 and proc.poll() is None:
        time.sleep(0.2)
        children = _children(proc.pid)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    lines = [line for line in err.splitlines() if not line.startswith("eval ")]
    assert proc.returncode == 143, err
    assert lines == ["vgs: stopped by SIGTERM; run the same command again to resume (finished "
                     "episodes are kept)"], err
    time.sleep(1.0)
    assert not {pid for pid in children if _alive(pid)}, "worker processes left running"
    _evaluate(out)
    _tables_equal("eval", out, reference["eval"])


def _children(pid: int) -> set[int]:
    found = set()
    for status in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = status.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.add(int(status.parent.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


# -- malformed files: the right syntax, the wrong shape (issue 53, item 4) ---------------------

def _json_shapes(name: str) -> list[tuple[str, object]]:
    """(what, how) pairs that keep a metadata file JSON but break its schema."""
    import json

    def edit(**changes: object):
        def apply(data: dict) -> dict:
            return {**data, **changes}
        return apply

    shapes: list[tuple[str, object]] = [("a list", lambda d: []), ("empty", lambda d: {}),
                                        ("config empty", edit(config={})),
                                        ("config a list", edit(config=[])),
                                        ("config.seed text", lambda d: {**d, "config": {
                                            **d["config"], "seed": "0"}})]
    if name == "run.json":
        shapes += [("mode 1", edit(mode=1)), ("mode other", edit(mode="greedy")),
                   ("schedule text", edit(schedule_episodes="six")),
                   ("hosts a dict", edit(hosts={}))]
    if name == "meta.json":
        shapes += [("episodes text", edit(episodes="8")), ("seed null", edit(seed=None)),
                   ("policy 3", edit(policy=3))]
    if name == "reproduce.json":
        shapes += [("profile 1", edit(profile=1)), ("walls text", edit(stage_wall_s={"t": "1"}))]
    del json
    return shapes


def _bytes_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in _files(folder)
            if "tensorboard" not in p.parts and p.name != ".lock"}


@pytest.mark.parametrize("kind", ["train", "eval"])
def test_malformed_metadata_is_refused_by_every_reader(
        kind: str, tmp_path: Path, reference, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """run.json / meta.json of the wrong shape or types: every reader refuses in one line (exit
    2) naming the file, and leaves every file of the folder byte-identical."""
    import json

    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    name = "run.json" if kind == "train" else "meta.json"
    readers = _readers(kind, tmp_path / "run", tmp_path / "x")
    if kind == "train":
        readers += [["heatmap", str(tmp_path / "run"), "--out", str(tmp_path / "x" / "h.png")],
                    ["curves", str(tmp_path / "run"), "--out", str(tmp_path / "x" / "c.png")]]
    for what, shape in _json_shapes(name):
        for argv in readers:
            for folder in ("run", "x"):
                shutil.rmtree(tmp_path / folder, ignore_errors=True)
            shutil.copytree(reference[kind], tmp_path / "run")
            path = tmp_path / "run" / name
            path.write_text(json.dumps(shape(json.loads(path.read_text()))))
            before = _bytes_of(tmp_path / "run")
            rc, lines = fakes.vgs(capsys, *argv)
            fakes.one_line(rc, lines, name)
            assert "Traceback" not in "".join(lines)
            assert _bytes_of(tmp_path / "run") == before, (what, argv[0])


def test_malformed_training_table_and_checkpoint_are_refused(
        tmp_path: Path, reference, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """An empty or wrong-header episodes.csv beside a checkpoint of 6 episodes is not "0/6 not
    started"; curves on it refuse; a checkpoint whose metadata has another shape is refused."""
    import json
    import zipfile

    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    run = tmp_path / "run"
    for what in ("empty", "header", "extra column", "text episode"):
        shutil.rmtree(run, ignore_errors=True)
        shutil.copytree(reference["train"], run)
        table = run / "episodes.csv"
        text = table.read_text()
        if what == "empty":
            table.write_text("")
        elif what == "header":
            table.write_text(text.replace("episode,", "epoch,", 1))
        elif what == "extra column":
            lines = text.splitlines()
            table.write_text("\n".join([lines[0] + ",foo"] + [ln + ",1" for ln in lines[1:]]))
        else:
            lines = text.splitlines()
            table.write_text("\n".join([lines[0], "x" + lines[1], *lines[2:]]) + "\n")
        before = _bytes_of(run)
        for argv in (["status", str(run)], ["curves", str(run), "--out",
                                              str(tmp_path / "c.png")],
                     ["train", "--mode", "vgs", "--episodes", "6", "--out", str(run),
                      *fakes.CLI_FLAGS]):
            rc, lines = fakes.vgs(capsys, *argv)
            if what == "extra column" and argv[0] == "train":
                continue  # (a resume rewrites the table from the checkpoint's rows)
            assert rc == 2, (what, argv[0], lines)
            fakes.one_line(rc, lines, "episodes.csv")
            assert _bytes_of(run) == before, (what, argv[0])
    # The checkpoint's metadata of another shape.
    shutil.rmtree(run)
    shutil.copytree(reference["train"], run)
    ckpt = run / "checkpoint.pt"
    with zipfile.ZipFile(ckpt) as zf:
        meta, tensors = json.loads(zf.read("meta.json")), zf.read("tensors.pt")
    for key, value in (("episode", "6"), ("agent", []), ("episode", -1)):
        with zipfile.ZipFile(ckpt, "w", zipfile.ZIP_STORED) as zf:
            zf.writestr("meta.json", json.dumps({**meta, key: value}))
            zf.writestr("tensors.pt", tensors)
        before = _bytes_of(run)
        for argv in _readers("train", run, tmp_path / "x"):
            shutil.rmtree(tmp_path / "x", ignore_errors=True)
            rc, lines = fakes.vgs(capsys, *argv)
            fakes.one_line(rc, lines, "checkpoint.pt")
            assert _bytes_of(run) == before, (key, argv[0])


def test_malformed_reproduction_and_merged_tables_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """reproduce.json of the wrong shape (``{}`` included) is refused by status and report, not
    read as the paper profile; a merged table with a foreign column or of other types is refused
    by the report; nothing in the folder changes."""
    import json

    from vgs.config import profile, to_dict

    data = Path(__file__).parents[1] / "data" / "report_small"
    run = tmp_path / "run"
    good = {"profile": "smoke", "config": to_dict(profile("smoke"))}
    for what, shape in _json_shapes("reproduce.json"):
        shutil.rmtree(run, ignore_errors=True)
        shutil.copytree(data, run)
        (run / "reproduce.json").write_text(json.dumps(shape(good)))
        before = _bytes_of(run)
        for argv in (["status", str(run)], ["report", str(run)],
                     ["grasp-sites", str(run), "--no-progress"]):
            rc, lines = fakes.vgs(capsys, *argv)
            assert rc == 2, (what, argv[0], lines)
            fakes.one_line(rc, lines, "reproduce.json")
            assert _bytes_of(run) == before, (what, argv[0])
    table = next(run.glob("eval/*/*/episodes.parquet"))
    for what in ("foreign column", "text success", "float index"):
        shutil.rmtree(run)
        shutil.copytree(data, run)
        df = pd.read_parquet(table)
        if what == "foreign column":
            df["foo"] = 1
        elif what == "text success":
            df["success"] = df["success"].map({True: "yes", False: "no"})  # (a legacy name)
        else:
            df["index"] = df["index"] + 0.5
        df.to_parquet(table)
        before = _bytes_of(run)
        rc, lines = fakes.vgs(capsys, "report", str(run))
        fakes.one_line(rc, lines, "episodes.parquet")
        assert _bytes_of(run) == before, what


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_second_signal_during_shutdown_changes_nothing(
        signum: int, code: int, tmp_path: Path, reference) -> None:
    """Two signals 20 ms apart (and a third later) end ``vgs train`` with the documented exit
    code and one line, never by the signal or with a traceback; the run then resumes to the
    uninterrupted table (issue 53, item 5)."""
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}
    for attempt in range(2):
        out = tmp_path / f"run{attempt}"
        argv = ["train", "--mode", "vgs", "--episodes", "6", "--out", str(out),
                *fakes.CLI_FLAGS]
        code_text = ("import os; os.cpu_count = lambda: 1; from experiments import fakes; "
                     f"fakes.run_cli({argv!r}, 0.05)")  # one torch thread, as the reference
        proc = subprocess.Popen([sys.executable, "-c", code_text], env=env,
                                stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (out / "episodes.csv").exists():
            time.sleep(0.02)
        time.sleep(0.05 * attempt)
        proc.send_signal(signum)
        time.sleep(0.02)
        proc.send_signal(signum)
        time.sleep(0.1)
        if proc.poll() is None:
            proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
        lines = [line for line in err.splitlines() if not line.startswith("train vgs")]
        assert proc.returncode == code, (attempt, proc.returncode, err)
        assert len(lines) == 1 and "Traceback" not in err, err
        _train(out)
        _tables_equal("train", out, reference["train"])


# -- foreign files: every folder proves whose it is (issue 53, item 1) -------------------------

@pytest.fixture(scope="module")
def other_seed(tmp_path_factory: pytest.TempPathFactory, fake_physics) -> Path:
    """A finished training run of seed 1 (the reference is seed 0)."""
    from vgs.config import override

    out = tmp_path_factory.mktemp("seed1") / "train"
    train(override(fakes.tiny_config(), "seed", 1), "vgs", out, progress=False, threads=1)
    return out


@pytest.mark.parametrize(("swap", "field"), [("checkpoint.pt", "seed"),
                                             ("run.json seed", "seed"),
                                             ("episodes.csv", "episodes.csv")])
def test_a_foreign_checkpoint_table_or_seed_is_refused_by_every_reader(
        swap: str, field: str, tmp_path: Path, reference, other_seed,
        capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Another seed's checkpoint or table copied into a run, or the seed edited in its
    run.json: train, status, export-policy and evaluate --policy refuse in one line naming the
    field, and change nothing."""
    import json

    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    run = tmp_path / "run"
    for argv in _readers("train", run, tmp_path / "x"):
        for folder in (run, tmp_path / "x"):
            shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(reference["train"], run)
        if swap == "run.json seed":
            meta = json.loads((run / "run.json").read_text())
            meta["config"]["seed"] = 1
            (run / "run.json").write_text(json.dumps(meta))
        else:
            shutil.copyfile(other_seed / swap, run / swap)
        before = _bytes_of(run)
        rc, lines = fakes.vgs(capsys, *argv)
        if swap == "run.json seed" and argv[0] == "train":
            fakes.one_line(rc, lines, "seed")  # (the request is seed 0: run.json's differs)
        else:
            assert rc == 2, (swap, argv[0], lines)
            fakes.one_line(rc, lines, field)
        assert _bytes_of(run) == before, (swap, argv[0])


def test_a_reproduction_checks_each_run_in_its_slots(tmp_path: Path, reference,
                                                     other_seed) -> None:
    """A seed-1 run (or one whose run.json says seed 0) in the vgs_s0 slot of a reproduction is
    refused, naming the field, not evaluated as vgs_s0."""
    import json

    from vgs.errors import VGSError
    from vgs.experiments.reproduce import Reproduction

    cfg = fakes.tiny_config()
    rep = Reproduction(cfg, tmp_path / "R", workers=1, progress=False)
    slot = tmp_path / "R" / "train" / "vgs_s0"
    shutil.copytree(reference["train"], slot)
    assert rep._trained(slot)
    for forge, words in (("run", "seed"), ("seed", "seed")):
        shutil.rmtree(slot)
        shutil.copytree(other_seed, slot)
        if forge == "seed":
            meta = json.loads((slot / "run.json").read_text())
            meta["config"]["seed"] = 0
            (slot / "run.json").write_text(json.dumps(meta))
        with pytest.raises(VGSError, match=words):
            rep._trained(slot)


def test_a_forged_or_missing_evaluation_is_refused_or_said(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A merged table changed after its evaluation wrote it (every success flipped, every time
    1 s) is refused by report and seeds, naming it; a missing or unfinished evaluation is said
    in the report, never left out silently (issue 53, item 2)."""
    import json

    from vgs.config import profile, to_dict
    from vgs.runfolder.common import table_digests

    data = Path(__file__).parents[1] / "data" / "report_small"
    run = tmp_path / "run"
    shutil.copytree(data, run)
    (run / "reproduce.json").write_text(json.dumps({"profile": "smoke",
                                                    "config": to_dict(profile("smoke"))}))
    for folder in run.glob("eval/*/*"):
        (folder / "summary.json").write_text(json.dumps(
            {"policy": folder.parent.name, "condition": folder.name,
             "tables_sha256": table_digests(folder)}))
    good = tmp_path / "good"
    shutil.copytree(run, good)
    table = run / "eval" / "vgs" / "nominal" / "episodes.parquet"
    df = pd.read_parquet(table)
    df["success"] = ~df["success"].astype(bool)
    df["assembly_time"] = 1.0
    df.to_parquet(table)
    before = _bytes_of(run)
    for argv in (["report", str(run)], ["seeds", str(run), "--out", str(tmp_path / "s")]):
        rc, lines = fakes.vgs(capsys, *argv)
        fakes.one_line(rc, lines, "episodes.parquet", "SHA-256")
        assert _bytes_of(run) == before, argv[0]
    shutil.rmtree(good / "eval" / "vgs" / "mass")
    (good / "eval" / "vgs" / "length" / "summary.json").unlink()
    rc, lines = fakes.vgs(capsys, "report", str(good))
    assert rc == 0, lines
    text = (good / "report.md").read_text()
    assert "vgs on mass (no table in eval/vgs/mass)" in text
    assert "vgs on length (unfinished: eval/vgs/length has no summary.json)" in text


# -- the small ones (issue 53, item 6) -----------------------------------------------------------

def test_a_finished_run_run_again_changes_nothing(tmp_path: Path, reference,
                                                  capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """No new TensorBoard events file, every file byte-identical."""
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    run = tmp_path / "run"
    shutil.copytree(reference["train"], run)
    before = _bytes_of(run)
    events = sorted((run / "tensorboard").rglob("*"))
    rc, lines = fakes.vgs(capsys, "train", "--mode", "vgs", "--episodes", "6", "--out", str(run),
                          *fakes.CLI_FLAGS)
    assert rc == 0, lines
    assert sorted((run / "tensorboard").rglob("*")) == events
    assert _bytes_of(run) == before


def test_a_refused_command_leaves_no_folder_behind(tmp_path: Path) -> None:
    from vgs.errors import ConfigError
    from vgs.runfolder.common import locked

    new = tmp_path / "new"
    with pytest.raises(ConfigError), locked(new):
        raise ConfigError("x", "refused after the lock")
    assert not new.exists()
    (tmp_path / "old").mkdir()
    with pytest.raises(ConfigError), locked(tmp_path / "old"):
        raise ConfigError("x", "refused after the lock")
    assert (tmp_path / "old").is_dir()  # a folder that was there stays


def test_publish_refuses_another_kind_of_folder_and_another_report(
        tmp_path: Path, reference, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from vgs.config import profile, to_dict

    data = Path(__file__).parents[1] / "data" / "report_small"
    repro = tmp_path / "R"
    shutil.copytree(data, repro)
    (repro / "reproduce.json").write_text(json.dumps({"profile": "smoke",
                                                      "config": to_dict(profile("smoke"))}))
    dest = tmp_path / "run"
    shutil.copytree(reference["train"], dest)
    before = _bytes_of(dest)
    rc, lines = fakes.vgs(capsys, "report", str(repro), "--publish", str(dest))
    fakes.one_line(rc, lines, "publish:", "training run")
    assert _bytes_of(dest) == before
    other = tmp_path / "other"
    other.mkdir()
    (other / "report.md").write_text("# another reproduction\n")
    rc, lines = fakes.vgs(capsys, "report", str(repro), "--publish", str(other))
    fakes.one_line(rc, lines, "publish:", "another reproduction")
    assert (other / "report.md").read_text() == "# another reproduction\n"


def test_a_full_disk_names_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                      monkeypatch: pytest.MonkeyPatch) -> None:
    import errno

    from vgs.cli import parser

    def full(args: object, cfg: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(parser, "cmd_train", full)
    rc, lines = fakes.vgs(capsys, "train", "--mode", "vgs", "--out", str(tmp_path / "r"),
                          "--profile", "smoke")
    fakes.one_line(rc, lines, str(tmp_path / "r"), "No space left on device")


def test_the_env_refuses_overrides_that_are_no_mapping() -> None:
    from vgs.envs.grasp_assemble import make_config
    from vgs.errors import ConfigError

    for overrides in ([("cell.peg.mass", 0.6)], {1: 0.6}, "cell.peg.mass=0.6"):
        with pytest.raises(ConfigError, match="overrides"):
            make_config("smoke", overrides)  # type: ignore[arg-type]


def _random_json(rnd: random.Random, depth: int = 0) -> object:
    choice = rnd.randrange(9 if depth < 3 else 6)
    if choice == 6:
        return [_random_json(rnd, depth + 1) for _ in range(rnd.randrange(3))]
    if choice == 7:
        return {rnd.choice(["mode", "config", "seed", "episodes", "a"]):
                _random_json(rnd, depth + 1) for _ in range(rnd.randrange(3))}
    return [None, True, rnd.randint(-3, 10**6), rnd.random() * 10, "", "x" * rnd.randrange(40),
            None, None, {"name": "smoke", "seed": -1}][choice]


def test_fuzz_of_the_metadata_readers(tmp_path: Path, reference,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Seeded random values in the fields of run.json, meta.json and reproduce.json (and random
    documents):
    ``vgs status`` reports or refuses in one line, never a traceback or another exit code."""
    import json

    from vgs.config import profile, to_dict

    rnd = random.Random(53)
    repro = tmp_path / "repro_source"
    shutil.copytree(Path(__file__).parents[1] / "data" / "report_small", repro)
    (repro / "reproduce.json").write_text(json.dumps({
        "profile": "smoke", "config": to_dict(profile("smoke")), "stage_wall_s": {"train": 1.0},
        "git_revision": "abc", "machine": "m", "command": "vgs reproduce"}))
    for kind, name, source in (("train", "run.json", reference["train"]),
                               ("eval", "meta.json", reference["eval"]),
                               ("repro", "reproduce.json", repro)):
        good = json.loads((source / name).read_text())
        run = tmp_path / kind
        shutil.copytree(source, run)
        for _ in range(40):
            doc = dict(good)
            if rnd.random() < 0.2:
                doc = _random_json(rnd)  # type: ignore[assignment]
            else:
                for key in rnd.sample(sorted(good), rnd.randrange(1, 3)):
                    doc[key] = _random_json(rnd)
            (run / name).write_text(json.dumps(doc))
            rc, lines = fakes.vgs(capsys, "status", str(run))
            assert rc in (0, 2), (doc, lines)
            if rc == 2:
                fakes.one_line(rc, lines)
