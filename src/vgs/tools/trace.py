"""An episode's data out of vgs: its per-tick trace as Parquet and, with the ``rerun`` extra, as
a Rerun recording (``vgs demo --trace/--rerun``, ``vgs evaluate --traces``).

Everything is derived after the episode from what :class:`vgs.control.robot.Robot` recorded
per control tick (:class:`vgs.control.robot.Trace`: time, tared wrench at the TCP in the world
frame, TCP position, the peg's lower end, phase, the whole ``qpos``) and the episode's model:
each recorded ``qpos`` is replayed through ``mujoco.mj_kinematics`` on a scratch ``MjData``
for the TCP's orientation; joint positions, finger width and the peg's pose are read from the
``qpos`` with the cell's ids. Nothing here runs inside the control loop.

Columns (:data:`vgs.columns.TRACE_COLUMNS`, units in their names): the TCP orientation is the
unit quaternion of the TCP site's rotation matrix ``R`` (sign fixed by ``w >= 0``); the peg's
tilt is ``acos(|R_peg[2, 2]|)``, the angle between its axis (its body z) and the vertical.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from vgs.columns import ARM_JOINTS, TRACE_COLUMNS, rounded, write_parquet
from vgs.errors import ConfigError
from vgs.sim.ids import cell_ids
from vgs.tools.demo import DemoResult

RERUN_HINT = "install the rerun extra: pip install 'vgs[rerun]' (rerun-sdk)"


def check_trace_name(name: str | Path) -> None:
    """Raise :class:`ConfigError` (``trace``) unless ``name`` ends in .parquet."""
    if not str(name).endswith(".parquet"):
        raise ConfigError("trace", f"{name}: the file must end in .parquet")


def require_rerun(name: str | Path) -> None:
    """Raise :class:`ConfigError` (``rerun``) unless ``name`` ends in .rrd and ``rerun-sdk`` is
    installed (checked before an episode, not after it)."""
    if not str(name).endswith(".rrd"):
        raise ConfigError("rerun", f"{name}: the file must end in .rrd")
    try:
        import rerun  # noqa: F401
    except ImportError:
        raise ConfigError("rerun", f"writing {name} needs rerun-sdk: {RERUN_HINT}") from None


def _quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix, with ``w >= 0``."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return -q if q[0] < 0 else q


def replay(result: DemoResult) -> dict[str, np.ndarray]:
    """The per-tick quantities read from the recorded states (no physics is stepped).

    Returns:
        ``tcp_quat`` (N, 4) w, x, y, z; ``joints`` (N, 6) [rad]; ``finger_width`` (N,) [m];
        ``peg_pos`` (N, 3) [m]; ``peg_quat`` (N, 4) w, x, y, z; ``peg_tilt`` (N,) [rad].
    """
    model = result.model
    if model is None:
        raise ConfigError("trace", "the episode carries no model to replay its states in")
    ids = cell_ids(model)
    if len(ids.arm_qpos) != len(ARM_JOINTS):
        raise ConfigError("trace", f"the arm has {len(ids.arm_qpos)} joints, the trace's "
                                   f"columns name {len(ARM_JOINTS)}")
    qpos = np.asarray(result.trace.qpos, dtype=float).reshape(-1, model.nq)
    data = mujoco.MjData(model)
    tcp_quat = np.zeros((len(qpos), 4))
    for i, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        tcp_quat[i] = _quat_wxyz(data.site_xmat[ids.tcp_site].reshape(3, 3))
    peg_quat = qpos[:, ids.peg_qpos + 3:ids.peg_qpos + 7]
    peg_quat = peg_quat / np.linalg.norm(peg_quat, axis=1, keepdims=True)
    w, x, y, _ = peg_quat.T
    # R[2, 2] of the quaternion (w, x, y, z): 1 - 2 (x^2 + y^2)
    tilt = np.arccos(np.clip(np.abs(1.0 - 2.0 * (x * x + y * y)), 0.0, 1.0))
    return {
        "tcp_quat": tcp_quat,
        "joints": qpos[:, ids.arm_qpos],
        "finger_width": qpos[:, ids.finger_qpos].sum(axis=1),
        "peg_pos": qpos[:, ids.peg_qpos:ids.peg_qpos + 3],
        "peg_quat": peg_quat * np.where(w < 0, -1.0, 1.0)[:, None],
        "peg_tilt": tilt,
    }


def trace_table(result: DemoResult) -> Any:
    """The episode's per-tick trace as a pandas DataFrame in :data:`TRACE_COLUMNS`' order."""
    import pandas as pd

    t = result.trace
    n = len(t.time)
    if n == 0:
        raise ConfigError("trace", "the episode recorded no ticks")
    poses = replay(result)
    tcp = 1000.0 * np.asarray(t.tcp, dtype=float).reshape(n, 3)
    wrench = np.asarray(t.wrench, dtype=float).reshape(n, 6)
    tip = 1000.0 * np.asarray(t.peg_tip, dtype=float).reshape(n, 3)
    cols: dict[str, Any] = {"time_s": np.asarray(t.time, dtype=float),
                            "phase": [str(p) for p in t.phase]}
    for k, a in enumerate("xyz"):
        cols[f"tcp_{a}_mm"] = tcp[:, k]
    for k, a in enumerate("wxyz"):
        cols[f"tcp_q{a}"] = poses["tcp_quat"][:, k]
    for k, a in enumerate("xyz"):
        cols[f"force_{a}_n"] = wrench[:, k]
    for k, a in enumerate("xyz"):
        cols[f"torque_{a}_nm"] = wrench[:, 3 + k]
    for k, j in enumerate(ARM_JOINTS):
        cols[f"joint_{j}_deg"] = np.degrees(poses["joints"][:, k])
    cols["finger_width_mm"] = 1000.0 * poses["finger_width"]
    for k, a in enumerate("xyz"):
        cols[f"peg_tip_{a}_mm"] = tip[:, k]
    cols["peg_tilt_deg"] = np.degrees(poses["peg_tilt"])
    for k, a in enumerate("xy"):
        cols[f"hole_{a}_mm"] = np.full(n, 1000.0 * float(result.hole_xy[k]))
    assert list(cols) == list(TRACE_COLUMNS)
    return pd.DataFrame(cols)


def trace_metadata(result: DemoResult) -> dict[str, str]:
    """The schema metadata of a trace file: the episode (seed, policy, outcome), the nominal
    hole and the source (:func:`vgs.runfolder.common.provenance`)."""
    from vgs.runfolder.common import provenance

    r = result.record
    return {**provenance(), "seed": str(r.seed), "policy": str(result.policy),
            "assembly_success": str(bool(r.success)).lower(),
            "assembly_time_s": f"{r.assembly_time:.3f}",
            "failure_reason": r.failure_reason,
            "nominal_hole_x_mm": f"{1000 * result.nominal_hole_xy[0]:.3f}",
            "nominal_hole_y_mm": f"{1000 * result.nominal_hole_xy[1]:.3f}",
            "hole_radius_mm": f"{1000 * result.hole_radius:.3f}",
            "peg_radius_mm": f"{1000 * result.peg_radius:.3f}"}


def write_trace(result: DemoResult, path: str | Path) -> Path:
    """Write the per-tick trace (:func:`trace_table`) to ``path`` (.parquet): each field's
    metadata holds its unit and description, the schema's the episode (:func:`trace_metadata`).
    Times are written to the ms (:func:`vgs.columns.rounded`)."""
    check_trace_name(path)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_parquet(rounded(trace_table(result)), path, trace_metadata(result))
    return path


# Entity paths of the Rerun recording (tests read them back).
RERUN_ENTITIES = (
    "heightmap/depth", "heightmap/color", "heightmap/grasp", "world/tcp", "world/tcp/origin",
    "world/peg", "world/peg/axis", "world/peg_tip", "world/hole", "ft/force/x", "ft/force/y",
    "ft/force/z", "ft/torque/x", "ft/torque/y", "ft/torque/z", "phase",
)
RERUN_Q_MAP = "heightmap/q"
TIMELINE = "sim_time"


def write_rerun(result: DemoResult, path: str | Path) -> Path:
    """Write the episode as a Rerun recording (``.rrd``, open it with ``rerun FILE``).

    Static: the heightmap the policy saw (``heightmap/depth`` [m], ``heightmap/color``), the
    chosen grasp point in its pixels (``heightmap/grasp``, x = column, y = row, pixel centres
    at +0.5), the policy's Q map (``heightmap/q``, where it has one), the hole's true centre
    at its entrance (``world/hole``), the peg's axis and the TCP in their own frames (``world``
    is z up). On the ``sim_time`` timeline, one row per control tick:
    the TCP's and the peg's poses (``world/tcp``, ``world/peg``: translation [m] and
    quaternion), the peg's lower end (``world/peg_tip``), the tared F/T wrench at the TCP in
    the world frame (``ft/force/<axis>`` [N], ``ft/torque/<axis>`` [N m]) and each phase change
    (``phase``, a text log).

    Raises:
        ConfigError: ``rerun`` on a bad name or without rerun-sdk (:func:`require_rerun`).
    """
    require_rerun(path)
    import rerun as rr

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    t = result.trace
    n = len(t.time)
    if n == 0:
        raise ConfigError("rerun", "the episode recorded no ticks")
    poses = replay(result)
    rec = rr.RecordingStream("vgs_episode", recording_id=f"vgs-{result.record.seed}-{path.name}")
    rec.save(path)
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    half = float(result.model.geom_size[cell_ids(result.model).peg_geom][1])
    rec.log("world/peg/axis", rr.LineStrips3D([[[0.0, 0.0, -half], [0.0, 0.0, half]]],
                                              radii=result.peg_radius), static=True)
    rec.log("world/tcp/origin", rr.Points3D([[0.0, 0.0, 0.0]], radii=0.004), static=True)
    hm = result.heightmap
    rec.log("heightmap/depth", rr.DepthImage(np.asarray(hm.depth, dtype=np.float32), meter=1.0),
            static=True)
    rec.log("heightmap/color", rr.Image(np.asarray(hm.color, dtype=np.uint8)), static=True)
    c = result.command
    if result.pixel is not None:
        row, col = result.pixel
    else:
        row, col = hm.world_to_pixel(c.x, c.y)
    rec.log("heightmap/grasp", rr.Points2D([[col + 0.5, row + 0.5]], radii=1.0), static=True)
    if result.q_map is not None:
        rec.log(RERUN_Q_MAP, rr.Tensor(np.asarray(result.q_map, dtype=np.float32),
                                       dim_names=("row", "col")), static=True)
    depth = float(result.hole_depth)
    rec.log("world/hole", rr.Points3D([[*result.hole_xy, depth]],
                                      radii=result.hole_radius), static=True)
    times = rr.TimeColumn(TIMELINE, duration=np.asarray(t.time, dtype=float))
    tcp = np.asarray(t.tcp, dtype=float).reshape(n, 3)
    xyzw = np.roll(poses["tcp_quat"], -1, axis=1)
    rec.send_columns("world/tcp", indexes=[times],
                     columns=rr.Transform3D.columns(translation=tcp, quaternion=xyzw))
    rec.send_columns("world/peg", indexes=[times],
                     columns=rr.Transform3D.columns(translation=poses["peg_pos"],
                                                    quaternion=np.roll(poses["peg_quat"], -1,
                                                                       axis=1)))
    rec.send_columns("world/peg_tip", indexes=[times],
                     columns=rr.Points3D.columns(positions=np.asarray(t.peg_tip, dtype=float)))
    wrench = np.asarray(t.wrench, dtype=float).reshape(n, 6)
    for k, name in enumerate(("force/x", "force/y", "force/z", "torque/x", "torque/y",
                              "torque/z")):
        rec.send_columns(f"ft/{name}", indexes=[times],
                         columns=rr.Scalars.columns(scalars=wrench[:, k]))
    changes = [i for i in range(n) if i == 0 or t.phase[i] != t.phase[i - 1]]
    rec.send_columns("phase", indexes=[rr.TimeColumn(TIMELINE, duration=[t.time[i]
                                                                         for i in changes])],
                     columns=rr.TextLog.columns(text=[str(t.phase[i]) for i in changes]))
    rec.flush()
    rec.disconnect()
    return path


def evaluation_outputs(cfg: Any, spec: Any, out: Path, videos: int = 0, traces: int = 0,
                       rows: Any = None, camera: str = "perspective",
                       **video: Any) -> tuple[list[Path], list[Path]]:
    """Videos and traces of the first test episodes of an evaluation, made after it: the first
    ``max(videos, traces)`` episodes are run again once each (:func:`vgs.tools.demo.
    evaluation_replays`); the first ``videos`` drawn to ``out/videos/episode_<index>.mp4``
    (``.gif`` without the MP4 writer; :func:`vgs.tools.demo.demo_video` from ``camera``), the
    first ``traces`` written to ``out/traces/episode_<index>.parquet`` (:func:`write_trace`).

    Args:
        cfg: The evaluation's configuration.
        spec: Its :class:`vgs.experiments.evaluate.EvalSpec`.
        out: Its folder.
        videos: Episodes to draw.
        traces: Episodes to trace.
        rows: The evaluation's table (an episode whose second run ends otherwise is reported).
        camera: The videos' camera (``perspective`` or ``hole``).
        **video: Keyword arguments of :func:`vgs.tools.demo.demo_video` (fps, speed, size).

    Returns:
        The written videos and traces.
    """
    from vgs.tools.demo import demo_video, evaluation_replays, video_suffix

    what = " and ".join(w for w, k in (("video", videos), ("trace", traces)) if k > 0)
    suffix = video_suffix() if videos > 0 else ""
    drawn: list[Path] = []
    traced: list[Path] = []
    count = max(videos, traces, 0)
    for k, (cell, result, index) in enumerate(evaluation_replays(cfg, spec, count, rows, what)):
        if k < videos:
            path = out / "videos" / f"episode_{index:04d}{suffix}"
            drawn.append(demo_video(result, cell, path, camera=camera, **video))
        if k < traces:
            traced.append(write_trace(result, out / "traces" / f"episode_{index:04d}.parquet"))
    return drawn, traced
