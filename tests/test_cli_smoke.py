"""Every ``vgs`` command in a subprocess, and bad input ending in one line and exit code 2."""

from __future__ import annotations

import csv
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import mujoco
import pytest

from vgs.experiments.sweep import COLUMNS

VGS = str(Path(sys.executable).with_name("vgs"))


def vgs(*argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([VGS, *argv], cwd=cwd, capture_output=True, text=True, timeout=300)


@pytest.mark.slow
def test_demo_json(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    proc = vgs("demo", "--seed", "2", "--json", "--profile", "smoke", "--out", str(out),
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert len(lines) == 1
    row = json.loads(lines[0], parse_constant=lambda c: pytest.fail(f"bare {c}: not strict"))
    assert row["seed"] == 2 and "time_search_s" in row and "grasp_offset_mm" in row
    assert "assembly_time_s" in row and "peg_length_mm" in row
    assert (out / "demo.png").stat().st_size > 10_000
    # progress on stderr while the episode runs, ending with its simulated time
    assert re.search(r"demo: episode done, \d+\.\d s simulated in \d+ s wall", proc.stderr)
    # the figure is there: refused before the episode, overwritten with --force
    again = vgs("demo", "--seed", "2", "--profile", "smoke", "--out", str(out), cwd=tmp_path)
    assert again.returncode == 2 and again.stderr.count("\n") == 1
    assert "demo.png exists; add --force" in again.stderr and again.stdout == ""
    forced = vgs("demo", "--seed", "2", "--json", "--profile", "smoke", "--out", str(out),
                 "--force", "--no-progress", cwd=tmp_path)
    assert forced.returncode == 0 and forced.stderr == "" and forced.stdout == proc.stdout


@pytest.mark.slow
def test_demo_table(tmp_path: Path) -> None:
    proc = vgs("demo", "--seed", "2", "--offset", "10", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    for phase in ("transport", "approach", "search", "slide", "align", "insert"):
        assert phase in proc.stdout
    assert "assembly time" in proc.stdout and "adjustments" in proc.stdout


@pytest.mark.slow
def test_sweep(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    proc = vgs("sweep", "--offsets-mm", "0,20", "--trials", "1", "--workers", "1", "--out",
               str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    with (out / "sweep.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 and tuple(rows[0]) == COLUMNS
    assert [float(r["offset_mm"]) for r in rows] == [0.0, 20.0]
    summary = json.loads((out / "summary.json").read_text())
    assert [s["n"] for s in summary["offsets"]] == [1, 1]
    assert (out / "sweep.png").stat().st_size > 10_000


def test_export_scene(tmp_path: Path) -> None:
    proc = vgs("export-scene", "--out", "scene.xml", "--peg-mass", "0.6", "--peg-length",
               "0.11", "--clearance", "0.0008", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "python -m mujoco.viewer --mjcf scene.xml" in proc.stdout  # how to open it
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "scene.xml"))
    peg = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "peg")
    assert model.body_mass[peg] == pytest.approx(0.6)


def test_model_info(tmp_path: Path) -> None:
    proc = vgs("model-info", "--backbone", "light", "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout)
    assert info["backbone"] == "light" and info["parameters"]["total"] > 0


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (("demo", "--peg-mass", "-1"), "--peg-mass"),
        (("demo", "--clearance", "0"), "hole.clearance"),
        (("demo", "--peg-diameter", "0.0315", "--clearance", "0.001"), "hole.clearance"),
        (("demo", "--offset", "51"), "offset"),
        (("sweep", "--offsets-mm", "0,60", "--trials", "1"), "offsets"),
        (("sweep", "--profile", "nope"), "profile"),
        (("export-scene", "--set", "cell.hole.segments=4"), "cell.hole.segments"),
        (("export-scene", "--peg-mass", "abc"), "argument --peg-mass"),
        (("frobnicate",), "argument COMMAND"),
        (("seeds", "nowhere", "--out", "x"), "seeds"),
        # each command takes only the flags it uses
        (("report", "DIR", "--peg-mass", "5"), "report"),
        (("heatmap", "RUN", "--out", "x.png", "--profile", "smoke"), "heatmap"),
        (("model-info", "--peg-mass", "5"), "model-info"),
        (("model-info", "--set", "cell.peg.mass=5"), "set"),
        (("config", "--set", "assembly.no_such_key=4"), "assembly.no_such_key"),
        (("config", "--set", "cell.peg=4"), "cell.peg"),
        (("config", "--set", "assembly.press_force=-4"), "assembly.press_force"),
    ],
)
def test_bad_input_one_line_exit_2(tmp_path: Path, argv: tuple[str, ...], field: str) -> None:
    proc = vgs(*argv, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"vgs: error: {field}: ")


def test_config_lists_every_key_with_its_value_and_doc(tmp_path: Path) -> None:
    proc = vgs("config", "--profile", "paper", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    backbone = next(line for line in lines if line.startswith("network.backbone "))
    _, value, doc = (part.strip() for part in re.split(r" = |  # ", backbone, maxsplit=2))
    assert value == "densenet121" and "light" in doc
    assert any(line.startswith("cell.peg.mass ") for line in lines)
    changed = vgs("config", "--profile", "quick", "--set", "assembly.press_force=4",
                  "--peg-mass", "0.6", cwd=tmp_path)
    assert changed.returncode == 0, changed.stderr
    values = {line.split(" = ")[0].strip(): line.split(" = ")[1].split("  # ")[0].strip()
              for line in changed.stdout.splitlines() if " = " in line}
    assert values["assembly.press_force"] == "4.0" and values["cell.peg.mass"] == "0.6"
    assert values["network.backbone"] == "light"  # the quick profile's
    doc = json.loads(vgs("config", "--json", cwd=tmp_path).stdout)
    assert {"key": "cell.peg.mass", "value": 0.55, "doc": "Peg mass [kg]."} in doc


@pytest.mark.slow
def test_evaluate_the_centre_of_mass_oracle(tmp_path: Path) -> None:
    """``--policy com-oracle`` on ``com`` pegs: the worker hands the oracle the true centre of
    mass, and the pads close on it (the row's ``grasp_offset_com_mm``)."""
    out = tmp_path / "eval"
    proc = vgs("evaluate", "--policy", "com-oracle", "--condition", "com", "--episodes", "1",
               "--workers", "1", "--profile", "smoke", "--no-progress", "--out", str(out),
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    import pandas as pd

    row = pd.read_parquet(out / "episodes.parquet").iloc[0]
    assert row["policy"] == "com-oracle" and row["peg_com_shift_mm"] == 20.0
    assert row["grasp_success"] and abs(row["grasp_offset_com_mm"]) < 2.0


@pytest.mark.slow
def test_evaluate_and_report(tmp_path: Path) -> None:
    out = tmp_path / "eval"
    proc = vgs("evaluate", "--policy", "center", "--condition", "mass", "--episodes", "2",
               "--workers", "2", "--profile", "smoke", "--no-progress", "--json",
               "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["episodes"] == 2
    import pandas as pd

    df = pd.read_parquet(out / "episodes.parquet")
    assert list(df["policy"]) == ["center", "center"] and set(df["condition"]) == {"mass"}
    for name in ("episodes.csv", "summary.json", "journal.jsonl", "meta.json"):
        assert (out / name).exists()
    bad = vgs("evaluate", "--policy", "nowhere", "--episodes", "1", "--out", str(out),
              cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.startswith("vgs: error: policy:")

    report_dir = tmp_path / "report"
    shutil.copytree(Path(__file__).parent / "data" / "report_small", report_dir)
    proc = vgs("report", str(report_dir), "--publish", str(tmp_path / "pub"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (report_dir / "report.md").exists() and (report_dir / "report.html").exists()
    assert (tmp_path / "pub" / "report.md").exists()
    assert (tmp_path / "pub" / "eval" / "vgs" / "mass" / "episodes.parquet").exists()
    assert not list((tmp_path / "pub").rglob("*.pt"))
    empty = vgs("report", str(tmp_path / "nothing"), cwd=tmp_path)
    assert empty.returncode == 2 and "no evaluation results" in empty.stderr


def test_seeds(tmp_path: Path) -> None:
    data = Path(__file__).parent / "data" / "report_small"
    proc = vgs("seeds", str(data), "--out", str(tmp_path / "seeds"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "| s0 |" in proc.stdout and "| **mean** |" in proc.stdout
    for name in ("seeds.md", "seeds.csv", "seeds.png"):
        assert (tmp_path / "seeds" / name).exists()


@pytest.mark.slow
def test_reproduce_quick_at_reduced_size(tmp_path: Path, quick_reproduction: Any) -> None:
    """The README's main job (``vgs reproduce --profile quick``), shrunk to seconds (run once
    per session by the ``quick_reproduction`` fixture of conftest.py)."""
    out, args, proc = (quick_reproduction.out, quick_reproduction.args,
                       quick_reproduction.proc)
    assert proc.returncode == 0, proc.stderr
    for mode in ("baseline", "vgs"):
        assert (out / "train" / f"{mode}_s0" / "checkpoint.pt").exists()
        for condition in ("nominal", "mass"):
            assert (out / "eval" / mode / condition / "episodes.parquet").exists()
    assert (out / "sweep" / "sweep.csv").exists()
    text = (out / "report.md").read_text()
    assert "## Headline" in text and "+13.83 %" in text and "Q heat maps" in text
    assert (out / "report.html").stat().st_size > 50_000
    # unattended (--no-progress): a log line per training checkpoint and per 5 % of evaluation
    assert "train vgs" in proc.stderr and "checkpoint at episode 2/2" in proc.stderr
    assert "eval 6 jobs: 6/6 episodes" in proc.stderr
    status = vgs("status", str(out), cwd=tmp_path)
    assert status.returncode == 0, status.stderr
    for line in ("train (2/2 done)", "evaluate (6/6 done)", "sweep (1/1 done)", "report: "):
        assert line in status.stdout, status.stdout
    sites_csv = tmp_path / "sites.csv"
    sites = vgs("grasp-sites", str(out), "--condition", "nominal", "--no-progress", "--csv",
                str(sites_csv), cwd=tmp_path)
    assert sites.returncode == 0, sites.stderr
    assert "**vgs, nominal**" in sites.stdout and "| along, either side [mm] |" in sites.stdout
    with sites_csv.open() as f:
        written = list(csv.DictReader(f))
    tested = sum(1 for table in (out / "eval").glob("*/nominal/episodes.csv")
                 for _ in csv.DictReader(table.open()))
    assert len(written) == tested
    assert all(r["across_mm"] for r in written if r["policy"] in ("baseline", "vgs"))
    one = vgs("grasp-sites", str(out), "--condition", "nominal", "--no-progress", "--csv",
              str(tmp_path / "sites1.csv"), "--workers", "1", cwd=tmp_path)
    assert one.returncode == 0, one.stderr
    assert (tmp_path / "sites1.csv").read_bytes() == sites_csv.read_bytes()
    assert one.stdout.replace("sites1.csv", "sites.csv") == sites.stdout
    # started again, every stage is already done: nothing is trained or evaluated again
    again = vgs(*args, cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    walls = json.loads((out / "reproduce.json").read_text())["stage_wall_s"]
    assert set(walls) >= {"train", "evaluate", "sweep", "report"}


@pytest.mark.slow
def test_reproduce_runs_only_the_stages_asked_for(tmp_path: Path) -> None:
    """``--stages sweep`` runs the sweep and writes no report; unknown stages are refused."""
    out = tmp_path / "rep"
    proc = vgs("reproduce", "--profile", "smoke", "--out", str(out), "--workers", "1",
               "--no-progress", "--stages", "sweep", "--set", "reproduce.sweep_offsets=1",
               "--set", "reproduce.sweep_trials=1", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (out / "sweep" / "summary.json").exists()
    assert not (out / "report.md").exists()
    bad = vgs("reproduce", "--profile", "smoke", "--out", str(tmp_path / "other"),
              "--stages", "train,deploy", cwd=tmp_path)
    assert bad.returncode == 2 and "stages" in bad.stderr
