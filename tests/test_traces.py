"""Episode data out (issue 54, item 1): ``vgs demo --trace/--rerun`` and ``vgs evaluate
--traces N`` write an episode's per-tick trace (Parquet, in the column vocabulary) and a Rerun
recording, read back here; the videos' close-up camera of the hole; the refusals."""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from vgs.assembly.record import PHASES
from vgs.cli import main
from vgs.columns import ARM_JOINTS, TRACE_COLUMNS, UNIT_SUFFIXES, column
from vgs.config import profile
from vgs.render import HOLE_CAMERA, gl_available, render_model
from vgs.sim import ur5
from vgs.sim.cell import build_spec

ROOT = Path(__file__).resolve().parents[1]
HAS_RERUN = importlib.util.find_spec("rerun") is not None
SMALL = ["--profile", "smoke", "--set", "cell.camera.size=64", "--set",
         "cell.camera.pixel_size=0.007"]
GL, GL_REASON = gl_available()


def vgs(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "vgs.cli", *args], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``vgs demo --seed 3 --trace t.parquet`` (and ``--rerun t.rrd`` with rerun-sdk) once."""
    cwd = tmp_path_factory.mktemp("demo")
    extra = ["--rerun", "t.rrd"] if HAS_RERUN else []
    proc = vgs("demo", "--seed", "3", "--json", "--trace", "t.parquet", *extra, "--out", ".",
               *SMALL, cwd=cwd)
    assert proc.returncode == 0, proc.stderr
    return {"cwd": cwd, "record": json.loads(proc.stdout), "stderr": proc.stderr}


# -- the vocabulary ----------------------------------------------------------------------------


def test_trace_columns_carry_their_units_and_the_docs_list_them() -> None:
    for name, col in TRACE_COLUMNS.items():
        assert column(name) == col and col.description and "\n" not in col.description, name
        if col.unit:
            assert col.kind == "float" and name.endswith(UNIT_SUFFIXES[col.unit]), name
        else:
            assert not any(name.endswith(s) for s in UNIT_SUFFIXES.values()), name
    assert [f"{j}_joint" for j in ARM_JOINTS] == list(ur5.JOINT_NAMES)
    text = (ROOT / "docs" / "columns.md").read_text()
    assert [n for n in TRACE_COLUMNS if f"`{n}`" not in text] == []
    for name, col in TRACE_COLUMNS.items():
        if "ground truth" in col.description:
            assert "analysis only" in col.description, name
    assert {n for n, c in TRACE_COLUMNS.items() if "analysis only" in c.description} == {
        "peg_tip_x_mm", "peg_tip_y_mm", "peg_tip_z_mm", "peg_tilt_deg", "hole_x_mm",
        "hole_y_mm"}


# -- vgs demo --trace ---------------------------------------------------------------------------


@pytest.mark.slow
def test_demo_trace_agrees_with_the_record(demo: dict[str, Any]) -> None:
    path = demo["cwd"] / "t.parquet"
    df = pd.read_parquet(path)
    record = demo["record"]
    assert list(df.columns) == list(TRACE_COLUMNS)
    schema = pq.read_schema(path)
    assert schema.field("force_z_n").metadata[b"unit"] == b"N"
    assert schema.field("torque_x_nm").metadata[b"unit"] == b"N m"
    assert b"analysis only" in schema.field("peg_tilt_deg").metadata[b"description"]
    assert schema.metadata[b"seed"] == b"3" and schema.metadata[b"policy"] == b"center"
    # one row per control tick, in order
    dt = profile("smoke").cell.sim.control_dt
    assert np.allclose(np.diff(df["time_s"]), dt, atol=1.5e-3)
    # each phase's ticks sum to the record's time of that phase
    ticks = df.groupby("phase").size()
    for phase in PHASES:
        assert ticks.get(phase, 0) * dt == pytest.approx(record[f"time_{phase}_s"], abs=1e-6)
    assembly = df[df["phase"].isin(PHASES)]
    assert len(assembly) * dt == pytest.approx(record["assembly_time_s"], abs=1e-6)
    assert list(dict.fromkeys(df["phase"]))[:2] == ["idle", "grasp"]
    assert df["phase"].iloc[-1] == "release"
    # the final time is the episode's: what the demo's progress line reported
    done = re.search(r"episode done, (\d+\.\d) s simulated", demo["stderr"])
    assert done and df["time_s"].iloc[-1] == pytest.approx(float(done.group(1)), abs=0.051)
    # the quaternion is a unit one; the peg ends upright in the hole, to its bottom
    q = df[["tcp_qw", "tcp_qx", "tcp_qy", "tcp_qz"]].to_numpy()
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0) and (q[:, 0] >= 0).all()
    end = df.iloc[-1]
    assert record["assembly_success"] and end["peg_tilt_deg"] < 1.0
    assert df["peg_tilt_deg"].iloc[0] == pytest.approx(90.0, abs=1.0)  # lying on the table
    assert end["peg_tilt_deg"] == pytest.approx(record["final_tilt_deg"], abs=0.05)
    tip_xy = np.hypot(end["peg_tip_x_mm"] - end["hole_x_mm"], end["peg_tip_y_mm"]
                      - end["hole_y_mm"])
    assert tip_xy < 1.0 and abs(end["peg_tip_z_mm"]) < 1.0
    hole = df[["hole_x_mm", "hole_y_mm"]].to_numpy() - 1000 * np.array(
        profile("smoke").cell.hole.nominal_xy)
    assert np.hypot(*hole[0]) == pytest.approx(record["hole_offset_mm"], abs=1e-3)
    # the gripper holds the 30 mm peg between grasp and release; open at the start
    held = df[df["phase"] == "search"]["finger_width_mm"]
    assert held.between(25.0, 30.5).all() and df["finger_width_mm"].iloc[0] > 60
    # the wrench is the controller's: the hole's surface pushes the peg up in the search
    assert df[df["phase"] == "search"]["force_z_n"].max() > 2.0


@pytest.mark.slow
@pytest.mark.skipif(not HAS_RERUN, reason="rerun-sdk not installed (the rerun extra)")
def test_demo_rerun_recording_reads_back_with_the_expected_entities(
        demo: dict[str, Any]) -> None:
    rrd = pytest.importorskip("rerun.chunk")
    if not hasattr(rrd, "RrdReader"):
        pytest.skip("this rerun-sdk has no rerun.chunk.RrdReader")
    from vgs.tools.trace import RERUN_ENTITIES

    reader = rrd.RrdReader(demo["cwd"] / "t.rrd")
    assert [s.application_id for s in reader.recordings()] == ["vgs_episode"]
    rows: dict[str, int] = {}
    for chunk in reader.stream():
        rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
    assert {f"/{e}" for e in RERUN_ENTITIES} <= set(rows)
    ticks = len(pd.read_parquet(demo["cwd"] / "t.parquet"))
    assert rows["/world/tcp"] == rows["/ft/force/z"] == rows["/world/peg_tip"] == ticks
    assert rows["/phase"] == 9  # idle, grasp, the six assembly phases, release


# -- vgs evaluate --traces ------------------------------------------------------------------


@pytest.mark.slow
def test_evaluate_traces_the_first_episodes_afterwards(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """One second run per episode serves its trace and, with OpenGL, its close-up video."""
    out = tmp_path / "ev"
    videos = ["--videos", "1", "--camera", "hole"] if GL else []
    assert main(["evaluate", "--policy", "center", "--episodes", "2", "--traces", "1", *videos,
                 "--workers", "1", "--no-progress", "--out", str(out), *SMALL]) == 0
    printed = capsys.readouterr()
    assert "ended otherwise" not in printed.err  # the second run is the same episode
    (path,) = (out / "traces").iterdir()
    assert path.name == "episode_0000.parquet" and f"traces {path}" in printed.out
    if GL:
        assert [v.stem for v in (out / "videos").iterdir()] == ["episode_0000"]
    table = pd.read_parquet(out / "episodes.parquet").set_index("index")
    trace, dt = pd.read_parquet(path), profile("smoke").cell.sim.control_dt
    assert trace["phase"].isin(PHASES).sum() * dt == pytest.approx(
        table.loc[0, "assembly_time_s"], abs=2e-3)
    assert pq.read_schema(path).metadata[b"seed"] == str(table.loc[0, "seed"]).encode()


def test_more_traces_or_videos_than_episodes_are_refused_before_evaluating(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for flag in ("--traces", "--videos"):
        out = tmp_path / flag.strip("-")
        assert main(["evaluate", "--policy", "center", "--episodes", "2", flag, "3",
                     "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "[0, 2] (the episodes evaluated), got 3" in err
        assert not out.exists()
    assert main(["evaluate", "--policy", "center", "--traces", "-1", "--out",
                 str(tmp_path / "n")]) == 2
    assert "--traces" in capsys.readouterr().err


def test_bad_trace_and_recording_names_are_refused_before_the_episode(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for flags, words in ((["--trace", "t.csv"], "t.csv: the file must end in .parquet"),
                         (["--rerun", "t.parquet"], "t.parquet: the file must end in .rrd")):
        assert main(["demo", "--out", str(tmp_path), *flags]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err
    assert main(["demo", "--out", str(tmp_path), "--camera", "side"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "invalid choice: 'side'" in err
    (tmp_path / "t.parquet").write_bytes(b"old")  # an existing trace: refused without --force
    assert main(["demo", "--out", str(tmp_path / "d"), "--trace",
                 str(tmp_path / "t.parquet")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "t.parquet exists; add --force" in err
    assert not (tmp_path / "d").exists()


def test_recording_without_rerun_is_refused_in_one_line(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['rerun'] = None; "
            "from vgs.cli import main; sys.exit(main(sys.argv[1:]))")
    proc = subprocess.run([sys.executable, "-c", code, "demo", "--rerun", "t.rrd", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert "vgs[rerun]" in proc.stderr and proc.stdout == ""


# -- the close-up camera of the hole ----------------------------------------------------------


def test_the_hole_camera_is_on_the_drawing_model_only() -> None:
    cfg = profile("smoke").cell
    import mujoco

    drawing = render_model(cfg)
    assert mujoco.mj_name2id(drawing, mujoco.mjtObj.mjOBJ_CAMERA, HOLE_CAMERA) >= 0
    simulated = build_spec(cfg).compile()
    assert mujoco.mj_name2id(simulated, mujoco.mjtObj.mjOBJ_CAMERA, HOLE_CAMERA) < 0


@pytest.mark.skipif(not GL, reason=f"no OpenGL for MuJoCo's renderer: {GL_REASON}")
def test_the_hole_camera_looks_at_the_hole() -> None:
    """The hole block (blue) fills the middle of the close-up; the perspective view shows it
    small."""
    from vgs.render import SceneRenderer

    cfg = profile("smoke").cell
    qpos = render_model(cfg).qpos0.copy()
    shares = {}
    for camera in ("perspective", HOLE_CAMERA):
        renderer = SceneRenderer(cfg, 160, 120, camera=camera)
        try:
            image = renderer.frame(qpos).astype(int)
        finally:
            renderer.close()
        blue = (image[..., 2] > image[..., 0] + 40) & (image[..., 2] > image[..., 1] + 20)
        shares[camera] = blue[40:80, 50:110].mean()
    assert shares[HOLE_CAMERA] > 0.5 > shares["perspective"]
