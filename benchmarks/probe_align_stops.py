"""How often does the alignment's moment limit stop a turn, per grasp offset? (An analysis probe;
figures only.)

The alignment (:meth:`vgs.assembly.contact.ContactPhases.align`) turns the peg about its
*nominal* lower end and stops a turn early where the measured moment about the pinch axis
opposes it beyond the moment limit. The probe runs whole episodes on the sweep's scenes
(``--seed`` as ``vgs sweep --seed``) and counts, per offset, the alignment's turns and those that
ended early (fewer control ticks than planned)::

    python benchmarks/probe_align_stops.py --scenes 6 --offsets-mm=0,35,-35

What it showed on 2026-12-02 (cell at ``43eafe6``, 6 scenes): centre grasp 2.2 adjustments per
episode and 1 of 52 turns stopped at the limit; +35 mm 5.2 adjustments and 73 of 124 turns
stopped; -35 mm 3.5 and 48 of 84.
"""

from __future__ import annotations

import argparse
import collections
from typing import Any

import numpy as np

from vgs.assembly import contact
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.config import profile


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=6)
    ap.add_argument("--offsets-mm", default="0,35,-35")
    ap.add_argument("--seed", type=int, default=0, help="root seed of the scenes")
    args = ap.parse_args(argv)

    counts: collections.Counter[str] = collections.Counter()
    rotate = contact.ContactPhases._rotate_about_tip

    def counted(self: Any, angle: float, n_ticks: int) -> None:
        start = self.robot.time
        rotate(self, angle, n_ticks)
        if self.robot.phase == "align":
            counts["turns"] += 1
            if self.robot.time - start < (max(1, n_ticks) - 0.5) * self.robot.dt:
                counts["stopped"] += 1

    contact.ContactPhases._rotate_about_tip = counted  # type: ignore[method-assign]
    runner = EpisodeRunner(profile("paper"))
    print("offset [mm]  adjustments per episode  alignment turns  stopped at the moment limit")
    for offset_mm in (float(x) for x in args.offsets_mm.split(",")):
        counts.clear()
        adjustments = []
        for scene in range(args.scenes):
            seed = int(np.random.SeedSequence([args.seed, scene]).generate_state(1)[0])
            record, _, _ = runner.run(seed, offset_policy(offset_mm / 1000.0))
            adjustments.append(record.adjustments)
        turns, stopped = counts["turns"], counts["stopped"]
        print(f"{offset_mm:+11.2f}  {np.mean(adjustments):23.2f}  {turns:15d}  "
              f"{stopped:5d} ({stopped / max(1, turns):.0%})")
    contact.ContactPhases._rotate_about_tip = rotate  # type: ignore[method-assign]
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
