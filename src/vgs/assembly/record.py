"""The episode record: everything one grasp-and-assemble episode produced."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from vgs.columns import PHASE_NAMES, normalize_row

PHASES: tuple[str, ...] = PHASE_NAMES


@dataclass
class EpisodeRecord:
    """One episode.

    Attributes:
        seed: Episode seed (cell randomisation and sensor noise).
        peg_mass: Peg mass [kg].
        peg_length: Peg length [m].
        peg_com_shift_mm: Ground truth: the peg's centre of mass from its middle along the
            axis, towards its heavy end [mm] (0: uniform).
        grasp_success: Whether the RG2 holds the peg after the lift.
        grasp_offset: Ground truth: signed distance along the peg axis from the peg's middle
            to the grasp point (the pads' midpoint after the lift) [m] (NaN when not
            grasped). For analysis only.
        grasp_offset_com: Ground truth: the same from the peg's centre of mass [m] (equal to
            ``grasp_offset`` on a uniform peg). For analysis only.
        across_mm: Ground truth (analysis only): the commanded grasp point's distance from
            the peg's axis across it, in the table plane, when the policy decided [mm].
        success: Whether the peg ended inserted to the insertion depth.
        failure_reason: Empty on success, else what stopped the episode (``grasp``,
            ``timeout:<phase>``, ``peg_lost``, ``unstable``, ``not_inserted``; in training only,
            ``cutoff:<phase>``, an assembly stopped at the reward threshold, and
            ``no_assembly``, a grasp not followed by an assembly).
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
        jaw_misalignment_deg: Ground truth (analysis only, never seen by a policy or the
            assembly module): the angle between the pads' long side as commanded and the
            peg's true axis in the table plane when the policy decided, folded into [0, 90]
            [deg]; 0 means the jaws close straight across the peg.
    """

    seed: int
    peg_mass: float
    peg_length: float
    peg_com_shift_mm: float = 0.0
    grasp_success: bool = False
    grasp_offset: float = math.nan
    grasp_offset_com: float = math.nan
    across_mm: float = math.nan
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
    jaw_misalignment_deg: float = math.nan

    def to_row(self) -> dict[str, object]:
        """Flat dict (one table row) in the column vocabulary of :mod:`vgs.columns`: names with
        their units (``peg_mass_kg``, ``peg_length_mm``, ``grasp_offset_mm``,
        ``assembly_success``, ``assembly_time_s``, ``peak_..._nm``), phase times as
        ``time_<phase>_s`` columns after the assembly time."""
        fields = dataclasses.asdict(self)
        times = fields.pop("phase_times")
        row: dict[str, object] = {}
        for key, value in normalize_row(fields).items():
            row[key] = value
            if key == "assembly_time_s":
                row.update({f"time_{p}_s": times.get(p, 0.0) for p in PHASES})
        return row
