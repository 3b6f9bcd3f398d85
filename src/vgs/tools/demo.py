"""One whole episode for people to look at: look, grasp, assemble, with the signals traced.

The grasp comes from the centre heuristic (with an ``offset`` along the peg), or from any
evaluation policy (:func:`vgs.rollout.policies.load_policy`: ``center``, ``random``, a
training run or policy folder), drawn as ``vgs evaluate`` draws it for the same episode seed.
:func:`demo_video` draws the traced episode afterwards, from its recorded states, as a video
with the phase and the wrist F/T reading written on every frame and, beside it, what the
policy saw: its Q heat map (a trained network) or the depth heightmap, with the chosen grasp.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from vgs.assembly.episode import EpisodeRunner, GraspCommand, offset_policy
from vgs.assembly.record import PHASES, EpisodeRecord
from vgs.config import CellConfig, ExperimentConfig, PegConfig, eval_scenes
from vgs.control.robot import Trace
from vgs.errors import ConfigError
from vgs.sim.camera import Heightmap
from vgs.sim.rg2 import PAD_HALF

if TYPE_CHECKING:
    from vgs.rollout.policies import Decision


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
        policy: The policy's name (``center``, ``random``, the run's mode, ...).
        q_map: The Q map (H, W) the grasp was chosen from (the chosen rotation's, for the
            rotation action), or None for a policy without one.
        pixel: The chosen pixel (row, col), or None where the policy chose no pixel.
        model: The model the episode ran in (its recorded states replay in it:
            :mod:`vgs.tools.trace`).
        hole_depth: Height of the hole's entrance above the table [m].
    """

    record: EpisodeRecord
    trace: Trace
    heightmap: Heightmap
    command: GraspCommand
    hole_xy: np.ndarray
    nominal_hole_xy: np.ndarray
    hole_radius: float
    peg_radius: float
    policy: str = "center"
    q_map: np.ndarray | None = None
    pixel: tuple[int, int] | None = None
    model: mujoco.MjModel | None = None
    hole_depth: float = 0.0


def check_offset(offset: float, peg: PegConfig) -> None:
    """Raise :class:`ConfigError` (``offset``) unless the pads' centre stays on the peg (as
    :func:`vgs.experiments.sweep.check_spec`: past ``L/2 - PAD_HALF`` the pads overhang the
    peg's end, which a policy's grasp can do too)."""
    limit = 0.5 * peg.length
    if not (math.isfinite(offset) and abs(offset) <= limit + 1e-12):
        raise ConfigError("offset", f"{offset * 1000:g} mm is off the peg: the pads' centre "
                                    f"stays on it for |offset| <= {limit * 1000:.1f} mm")


class EpisodeTicker:
    """Reports an episode's simulated time while it runs: a thread reads the cell's clock
    (``data.time``, which the episode's reset sets to 0) every ``interval`` wall seconds and
    calls ``report(simulated seconds, wall seconds)``; nothing of the episode is touched.

    Use as a context manager around the episode.
    """

    def __init__(self, clock: Callable[[], float], report: Callable[[float, float], None],
                 interval: float = 2.0) -> None:
        self._clock = clock
        self._report = report
        self._interval = interval
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True, name="demo-progress")
        self._start = 0.0

    def _loop(self) -> None:
        while not self._stop.wait(self._interval):
            self._report(float(self._clock()), time.monotonic() - self._start)

    def __enter__(self) -> EpisodeTicker:
        self._start = time.monotonic()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def run_demo(cfg: ExperimentConfig, seed: int, offset: float = 0.0, policy: str | None = None,
             peg: PegConfig | None = None,
             progress: Callable[[float, float], None] | None = None) -> DemoResult:
    """Run one traced episode.

    Args:
        cfg: Experiment configuration.
        seed: Episode seed.
        offset: Grasp offset along the visible peg axis [m] for the centre heuristic (no
            ``policy``); 0 is the centre.
        policy: A policy spec (:func:`vgs.rollout.policies.load_policy`); it chooses as in
            ``vgs evaluate`` (its generator seeded ``[seed, 2]``), so an evaluation's episode
            of that seed and peg is the same episode.
        peg: The episode's peg (default: the configured one).
        progress: Called every 2 s of wall time during the episode with the simulated and
            the wall seconds so far (:class:`EpisodeTicker`).

    Raises:
        ConfigError: If the offset puts the pads off the peg, an offset comes with a policy, or
            the policy spec names nothing usable.
    """
    check_offset(offset, cfg.cell.peg)
    runner = EpisodeRunner(cfg)
    chosen: dict[str, Decision] = {}
    grasp: Any
    if policy is None:
        grasp = offset_policy(offset)
        name = "center" if offset == 0 else f"center {offset * 1000:+g} mm"
    else:
        if offset != 0:
            raise ConfigError("offset", "applies to the centre heuristic; leave it out with "
                                        "--policy")
        from vgs.rollout.policies import episode_policy, load_policy

        chooser = load_policy(policy, cfg)
        name = str(getattr(chooser, "label", policy))
        # its generator as vgs evaluate draws it
        grasp = episode_policy(chooser, np.random.default_rng([seed, 2]), chosen)

    if progress is None:
        record, robot, hm = runner.run(seed, grasp, peg=peg, trace=True)
    else:
        cell, _ = runner.cell(peg or cfg.cell.peg)  # the cell the episode will step
        with EpisodeTicker(lambda: cell.data.time, progress):
            record, robot, hm = runner.run(seed, grasp, peg=peg, trace=True)
    decision = chosen.get("decision")
    command = decision.command if decision is not None else offset_policy(offset)(hm)
    pixel = (decision.row, decision.col) if decision is not None and decision.row >= 0 else None
    q_map = None
    agent = getattr(chooser, "agent", None) if policy is not None else None
    if agent is not None and pixel is not None:
        q_map = agent.q_values(hm.color, hm.depth)[max(decision.rotation, 0)]
    cell = robot.cell
    return DemoResult(
        record=record,
        trace=robot.trace,
        heightmap=hm,
        command=command,
        hole_xy=np.array(cell.hole_xy, dtype=float),
        nominal_hole_xy=np.array(cfg.cell.hole.nominal_xy, dtype=float),
        hole_radius=cfg.cell.hole.radius,
        peg_radius=(peg or cfg.cell.peg).radius,
        policy=name,
        q_map=q_map,
        pixel=pixel,
        model=cell.model,
        hole_depth=cfg.cell.hole.depth,
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
        f"grasp offset    {record.grasp_offset * 1000:+.1f} mm from the middle, "
        f"{record.grasp_offset_com * 1000:+.1f} mm from the centre of mass "
        f"({record.peg_com_shift_mm:g} mm from the middle), {record.across_mm:.1f} mm beside "
        "the axis",
        f"hole offset     {record.hole_offset_mm:.1f} mm from nominal",
        f"final tilt      {record.final_tilt_deg:.2f} deg",
        f"insertion depth {record.insertion_depth_mm:.1f} mm",
    ]
    return "\n".join(lines)


def frame_text(result: DemoResult, index: int, speed: float) -> list[str]:
    """The lines written on the frame of tick ``index``: time, phase, F/T reading."""
    trace = result.trace
    f = trace.wrench[index][:3]
    m = trace.wrench[index][3:]
    return [
        f"{result.policy}, seed {result.record.seed}   t = {trace.time[index]:5.1f} s  "
        f"(x{speed:g})",
        f"phase: {trace.phase[index]}",
        f"F [N]    {f[0]:+6.1f} {f[1]:+6.1f} {f[2]:+6.1f}",
        f"M [N m]  {m[0]:+6.2f} {m[1]:+6.2f} {m[2]:+6.2f}",
    ]


def outcome_text(record: EpisodeRecord) -> str:
    """One line: assembled and how fast, or why not."""
    if record.success:
        return f"assembled in {record.assembly_time:.1f} s"
    return f"not assembled ({record.failure_reason})"


def policy_panel(result: DemoResult, size: int, half: float = 0.08) -> np.ndarray:
    """What the policy saw, as an RGB uint8 (size, size, 3) image: its Q heat map over the
    heightmap (a trained network) or the depth heightmap (a heuristic), cropped to a square of
    side ``2 half`` [m] around the grasp, with the chosen grasp marked (pads and point)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    hm, c = result.heightmap, result.command
    h, w = hm.depth.shape
    x0, y0 = hm.origin
    ext = [1000 * x0, 1000 * (x0 + w * hm.pixel_size), 1000 * y0, 1000 * (y0 + h * hm.pixel_size)]
    fig = Figure(figsize=(size / 100, size / 100), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    if result.q_map is not None:
        ax.imshow(hm.color, origin="lower", extent=ext)
        q = np.ma.masked_where(hm.depth <= 0.005, result.q_map)  # the pixels it chose among
        im = ax.imshow(q, origin="lower", extent=ext, cmap="inferno", alpha=0.85)
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.02).ax.tick_params(labelsize=6)
        title = f"{Path(str(result.policy)).name}: Q on the peg, grasp"
    else:
        ax.imshow(1000 * hm.depth, origin="lower", extent=ext, cmap="viridis")
        title = f"{Path(str(result.policy)).name}: depth heightmap, grasp"
    along = np.array([math.cos(c.yaw), math.sin(c.yaw)])
    across = np.array([-along[1], along[0]])
    for side in (-1.0, 1.0):
        mid = np.array([c.x, c.y]) + side * (result.peg_radius + 0.003) * across
        ends = 1000 * np.array([mid - PAD_HALF[0] * along, mid + PAD_HALF[0] * along])
        ax.plot(ends[:, 0], ends[:, 1], color="cyan", lw=3, solid_capstyle="butt")
    ax.plot(1000 * c.x, 1000 * c.y, "+", color="cyan", ms=10, mew=2)
    ax.set(xlim=(1000 * (c.x - half), 1000 * (c.x + half)),
           ylim=(1000 * (c.y - half), 1000 * (c.y + half)), xticks=[], yticks=[])
    ax.set_title(title, fontsize=8)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[:size, :size, :3]
    return np.pad(image, ((0, size - image.shape[0]), (0, size - image.shape[1]), (0, 0)),
                  constant_values=255)


MAX_VIDEO_BYTES = 2 * 2**30  # the frames of one video, held in memory until it is written


def demo_video(result: DemoResult, cell: CellConfig, path: str | Path, fps: float = 15.0,
               speed: float = 4.0, width: int = 480, height: int = 360,
               hold_s: float = 1.5, panel: bool | None = None,
               camera: str = "perspective") -> Path:
    """Render a traced episode from a camera of :mod:`vgs.render` and write it as a video.

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
        panel: Put :func:`policy_panel` (height x height px) to the right of every frame
            (default: where the policy has a Q map, a trained network).
        camera: ``perspective`` (robot, workspace and hole) or ``hole`` (a close-up of the
            hole: :data:`vgs.render.HOLE_CAMERA`).

    Returns:
        The written file.

    Raises:
        ConfigError: ``video`` on a bad file name, ``video.fps`` / ``video.speed`` if not
            positive, ``video.size`` on a bad size, ``camera`` on an unknown camera.
        GLUnavailableError: If no OpenGL context can be made.
    """
    from vgs.render import SceneRenderer, annotate, frame_indices, write_video

    if not (math.isfinite(fps) and fps > 0):
        raise ConfigError("video.fps", f"must be > 0, got {fps}")
    if not (math.isfinite(speed) and speed > 0):
        raise ConfigError("video.speed", f"must be > 0, got {speed}")
    trace = result.trace
    if not trace.qpos:
        raise ConfigError("video", "the episode recorded no states")
    indices = frame_indices(np.asarray(trace.time), fps, speed)
    frame_bytes = width * height * 3 * (2 if panel or result.q_map is not None else 1)
    if (len(indices) + hold_s * fps) * frame_bytes > MAX_VIDEO_BYTES:
        raise ConfigError("video", f"{len(indices)} frames of {width}x{height} px would hold "
                                   f"{len(indices) * frame_bytes / 2**30:.1f} GiB; at most "
                                   f"{MAX_VIDEO_BYTES / 2**30:g} GiB (a higher --video-speed or "
                                   "a lower --video-fps)")
    mocap = np.array([*result.hole_xy, 0.0])
    renderer = SceneRenderer(cell, width, height, camera=camera)
    try:
        frames = [annotate(renderer.frame(trace.qpos[i], mocap), frame_text(result, i, speed))
                  for i in indices]
        final = annotate(renderer.frame(trace.qpos[-1], mocap),
                         [*frame_text(result, len(trace.qpos) - 1, speed)[:2],
                          outcome_text(result.record)])
    finally:
        renderer.close()
    frames += [final] * max(1, int(round(hold_s * fps)))
    if panel or (panel is None and result.q_map is not None):
        side = policy_panel(result, height)
        frames = [np.concatenate([f, side], axis=1) for f in frames]
    return write_video(path, frames, fps)


def evaluation_replays(cfg: ExperimentConfig, spec: Any, count: int, rows: Any = None,
                       what: str = "video") -> Iterator[tuple[CellConfig, DemoResult, int]]:
    """The first ``count`` test episodes of an evaluation run again after it, each by its seed
    and peg with a trace (:func:`run_demo`, the policy choosing as in the evaluation), in index
    order. Nothing is drawn or traced inside the evaluation.

    Args:
        cfg: The evaluation's configuration.
        spec: Its :class:`vgs.experiments.evaluate.EvalSpec` (policy, condition, seed): the
            scenes are the condition's test scenes (:func:`vgs.config.eval_scenes`).
        count: Episodes to run again (the first ones, in index order).
        rows: The evaluation's table (``index``, ``assembly_time_s``); an episode whose second
            run ends otherwise is reported on stderr.
        what: What the episode is run again for (the stderr line's words).

    Yields:
        The episode's cell (its peg), the traced episode and its index.
    """
    import sys
    from dataclasses import replace

    for task in eval_scenes(cfg.cell.peg, cfg.eval, spec.condition, spec.seed, max(0, count)):
        result = run_demo(cfg, task.seed, policy=spec.policy, peg=task.peg)
        if rows is not None:
            row = rows[rows["index"] == task.index]
            was = float(row["assembly_time_s"].iloc[0]) if len(row) else math.nan
            now = result.record.assembly_time
            if not (was == now or (math.isnan(was) and math.isnan(now))):
                print(f"vgs: episode {task.index} ended otherwise when run again for its {what} "
                      f"({now:.3f} s, the table has {was:.3f} s)", file=sys.stderr)
        yield replace(cfg.cell, peg=task.peg), result, task.index


def video_suffix() -> str:
    """``.mp4``, or ``.gif`` without the MP4 writer."""
    from vgs.render import require_video_writer

    try:
        require_video_writer("x.mp4")
    except ConfigError:
        return ".gif"
    return ".mp4"
