"""The episode record: everything one grasp-and-assemble episode produced."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

PHASES: tuple[str, ...] = ("transport", "approach", "search", "slide", "align", "insert")


@dataclass
class EpisodeRecord:
    """One episode.

    Attributes:
        seed: Episode seed (cell randomisation and sensor noise).
        peg_mass: Peg mass [kg].
        peg_length: Peg length [m].
        grasp_success: Whether the RG2 holds the peg after the lift.
        grasp_offset: Ground truth: signed distance along the peg axis from the centre of mass
            to the grasp point [m] (NaN when not grasped). For analysis only.
        success: Whether the peg ended inserted to the insertion depth.
        failure_reason: Empty on success, else what stopped the episode (``grasp``,
            ``timeout:<phase>``, ``dropped``, ``unstable``, ``not_inserted``).
        assembly_time: Simulated seconds from the end of the grasp to the end of insertion.
        phase_times: Simulated seconds spent in each phase of :data:`PHASES`.
        adjustments: Number of alignment adjustments (wiggle iterations, paper Section 2.2).
        retries: New searches after a wrong contact-state decision (lost alignment or a stalled
            insertion).
        hole_offset_mm: Ground truth displacement of the hole from its nominal position [mm].
        final_tilt_deg: Ground truth tilt of the peg axis from vertical at the end [deg].
        insertion_depth_mm: Ground truth depth of the peg's lower end below the entrance [mm].
        peak_moment_measured: Largest moment about the pinch axis the controller measured with
            the F/T sensor in contact [N m].
        peg_turn_deg: Ground truth (analysis only): the largest angle by which the peg's axis
            turned in the pads (in the tool frame) between the end of the grasp and the release,
            sampled at 25 Hz [deg].
        peak_grasp_moment: Ground truth (analysis only): largest moment about the pinch axis
            that the fingers' contact forces exerted on the peg, about the TCP, sampled at 25 Hz
            during the assembly [N m].
    """

    seed: int
    peg_mass: float
    peg_length: float
    grasp_success: bool = False
    grasp_offset: float = math.nan
    success: bool = False
    failure_reason: str = ""
    assembly_time: float = math.nan
    phase_times: dict[str, float] = field(default_factory=lambda: {p: 0.0 for p in PHASES})
    adjustments: int = 0
    retries: int = 0
    hole_offset_mm: float = math.nan
    final_tilt_deg: float = math.nan
    insertion_depth_mm: float = math.nan
    peak_moment_measured: float = math.nan
    peg_turn_deg: float = math.nan
    peak_grasp_moment: float = math.nan

    def to_row(self) -> dict[str, object]:
        """Flat dict (one table row): phase times become ``time_<phase>_s`` columns."""
        row = {k: v for k, v in dataclasses.asdict(self).items() if k != "phase_times"}
        for phase in PHASES:
            row[f"time_{phase}_s"] = self.phase_times.get(phase, 0.0)
        row["grasp_offset_mm"] = self.grasp_offset * 1000.0
        return row
