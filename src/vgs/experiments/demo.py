"""One whole episode for people to look at: look, grasp, assemble, with the signals traced.

:func:`demo_video` draws the traced episode afterwards, from its recorded states, as a video
with the phase and the wrist F/T reading written on every frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vgs.assembly.episode import EpisodeRunner, GraspCommand, offset_policy
from vgs.assembly.record import PHASES, EpisodeRecord
from vgs.config import CellConfig, ExperimentConfig, PegConfig
from vgs.control.robot import Trace
from vgs.errors import ConfigError
from vgs.sim.camera import Heightmap
from vgs.sim.rg2 import PAD_HALF


@dataclass(frozen=True)
class DemoResult:
    """A traced episode.

    Attributes:
        record: The episode record.
        trace: Per-tick signals (time, F/T wrench at the TCP, TCP, peg tip, phase).
        heightmap: What the grasp policy saw.
        command: The grasp the policy chose.
        hole_xy: True hole centre of the episode (world x, y) [m].
        nominal_hole_xy: Nominal hole centre, where the search starts [m].
        hole_radius: Hole radius [m].
        peg_radius: Peg radius [m].
    """

    record: EpisodeRecord
    trace: Trace
    heightmap: Heightmap
    command: GraspCommand
    hole_xy: np.ndarray
    nominal_hole_xy: np.ndarray
    hole_radius: float
    peg_radius: float


def check_offset(offset: float, peg: PegConfig) -> None:
    """Raise :class:`ConfigError` (``offset``) unless both pads stay on the peg."""
    limit = 0.5 * peg.length - PAD_HALF[0]
    if not (math.isfinite(offset) and abs(offset) <= limit + 1e-12):
        raise ConfigError("offset", f"{offset * 1000:g} mm is off the peg: the pads stay on it "
                                    f"for |offset| <= {limit * 1000:.1f} mm")


def run_demo(cfg: ExperimentConfig, seed: int, offset: float = 0.0) -> DemoResult:
    """Run one traced episode grasping ``offset`` metres from the visible peg centre.

    Args:
        cfg: Experiment configuration.
        seed: Episode seed.
        offset: Grasp offset along the visible peg axis [m]; 0 is the centre heuristic.

    Raises:
        ConfigError: If the offset puts the pads off the peg.
    """
    check_offset(offset, cfg.cell.peg)
    runner = EpisodeRunner(cfg)
    policy = offset_policy(offset)
    record, robot, hm = runner.run(seed, policy, trace=True)
    cell = robot.cell
    return DemoResult(
        record=record,
        trace=robot.trace,
        heightmap=hm,
        command=policy(hm),
        hole_xy=np.array(cell.hole_xy, dtype=float),
        nominal_hole_xy=np.array(cfg.cell.hole.nominal_xy, dtype=float),
        hole_radius=cfg.cell.hole.radius,
        peg_radius=cfg.cell.peg.radius,
    )


def format_report(record: EpisodeRecord) -> str:
    """Phase table (simulated seconds) and the episode's outcome as plain text."""
    width = max(len(p) for p in PHASES)
    lines = [f"{'phase'.ljust(width)}  time [s]", f"{'-' * width}  --------"]
    for phase in PHASES:
        lines.append(f"{phase.ljust(width)}  {record.phase_times.get(phase, 0.0):8.2f}")
    outcome = "yes" if record.success else f"no ({record.failure_reason})"
    lines += [
        "",
        f"seed            {record.seed}",
        f"success         {outcome}",
        f"assembly time   {record.assembly_time:.2f} s (simulated)",
        f"adjustments     {record.adjustments}",
        f"grasp offset    {record.grasp_offset * 1000:+.1f} mm from the centre of mass",
        f"hole offset     {record.hole_offset_mm:.1f} mm from nominal",
        f"final tilt      {record.final_tilt_deg:.2f} deg",
        f"insertion depth {record.insertion_depth_mm:.1f} mm",
    ]
    return "\n".join(lines)


def frame_indices(times: np.ndarray, fps: float, speed: float) -> np.ndarray:
    """Indices of the ticks shown as video frames: one every ``speed / fps`` simulated seconds.

    Args:
        times: Simulated time of each recorded tick [s], increasing.
        fps: Video frames per second.
        speed: Simulated seconds per second of video.

    Returns:
        For each frame, the index of the last tick at or before its time.
    """
    if times.size == 0:
        return np.zeros(0, dtype=int)
    step = speed / fps
    frame_times = times[0] + step * np.arange(int((times[-1] - times[0]) / step) + 1)
    return np.clip(np.searchsorted(times, frame_times + 1e-9, side="right") - 1, 0,
                   times.size - 1)


def frame_text(result: DemoResult, index: int, speed: float) -> list[str]:
    """The lines written on the frame of tick ``index``: time, phase, F/T reading."""
    trace = result.trace
    f = trace.wrench[index][:3]
    m = trace.wrench[index][3:]
    return [
        f"seed {result.record.seed}   t = {trace.time[index]:5.1f} s  (x{speed:g})",
        f"phase: {trace.phase[index]}",
        f"F [N]    {f[0]:+6.1f} {f[1]:+6.1f} {f[2]:+6.1f}",
        f"M [N m]  {m[0]:+6.2f} {m[1]:+6.2f} {m[2]:+6.2f}",
    ]


def outcome_text(record: EpisodeRecord) -> str:
    """One line: assembled and how fast, or why not."""
    if record.success:
        return f"assembled in {record.assembly_time:.1f} s"
    return f"not assembled ({record.failure_reason})"


def demo_video(result: DemoResult, cell: CellConfig, path: str | Path, fps: float = 15.0,
               speed: float = 4.0, width: int = 480, height: int = 360,
               hold_s: float = 1.5) -> Path:
    """Render a traced episode from the ``perspective`` camera and write it as a video.

    The states recorded per control tick (``trace.qpos``) are drawn after the episode, one
    every ``speed / fps`` simulated seconds; every frame carries the simulated time, the phase
    and the tared wrist F/T reading at the TCP; the last frame, with the outcome, is held for
    ``hold_s`` seconds.

    Args:
        result: A traced episode (:func:`run_demo`).
        cell: The cell the episode ran in (the peg to draw).
        path: ``.mp4`` or ``.gif`` file.
        fps: Video frames per second.
        speed: Simulated seconds per second of video.
        width: Frame width [px].
        height: Frame height [px].
        hold_s: Seconds the last frame is shown.

    Returns:
        The written file.

    Raises:
        ConfigError: ``video`` on a bad file name, ``video.fps`` / ``video.speed`` if not
            positive, ``video.size`` on a bad size.
        GLUnavailableError: If no OpenGL context can be made.
    """
    from vgs.render import SceneRenderer, annotate, write_video

    if not (math.isfinite(fps) and fps > 0):
        raise ConfigError("video.fps", f"must be > 0, got {fps}")
    if not (math.isfinite(speed) and speed > 0):
        raise ConfigError("video.speed", f"must be > 0, got {speed}")
    trace = result.trace
    if not trace.qpos:
        raise ConfigError("video", "the episode recorded no states")
    indices = frame_indices(np.asarray(trace.time), fps, speed)
    mocap = np.array([*result.hole_xy, 0.0])
    renderer = SceneRenderer(cell, width, height)
    try:
        frames = [annotate(renderer.frame(trace.qpos[i], mocap), frame_text(result, i, speed))
                  for i in indices]
        final = annotate(renderer.frame(trace.qpos[-1], mocap),
                         [*frame_text(result, len(trace.qpos) - 1, speed)[:2],
                          outcome_text(result.record)])
    finally:
        renderer.close()
    frames += [final] * max(1, int(round(hold_s * fps)))
    return write_video(path, frames, fps)
