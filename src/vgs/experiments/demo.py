"""One whole episode for people to look at: look, grasp, assemble, with the signals traced."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vgs.assembly.episode import EpisodeRunner, GraspCommand, offset_policy
from vgs.assembly.record import PHASES, EpisodeRecord
from vgs.config import ExperimentConfig, PegConfig
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
