"""How a grasp whose jaws are turned away from the peg's axis holds the peg, and what that does to
the assembly. (An analysis probe of the cell's physics; figures only.)

Each episode grasps the peg at its centre (the heightmap's axis, as ``offset_policy(0)``) with
the pads' long side turned ``phi`` degrees away from the peg's axis, the misalignment a learned
policy's discrete rotations leave: with R rotations the jaw directions lie 360 / R degrees
apart, and the grasp is symmetric under a half turn, so the nearest lies up to 180 / R degrees
from the axis (11.25 deg at the paper's R = 16). The probe prints, per angle, the peg's yaw in
the pads after the grasp (ground truth: the angle between its axis and the pads' long side,
whether the pinch squared it up), the assemblies that succeeded, their mean time and the
failures::

    python benchmarks/probe_jaw_misalignment.py --angles 0,2,4,6,8,11.25 --episodes 6
    python benchmarks/probe_jaw_misalignment.py --set cell.gripper.stiction=False

What it showed on 2026-12-02 (AMD EPYC host, MuJoCo 4.0.0, scenes 0-3): the pinch does not
square the peg up (5.6 deg stays 5.1-5.6 deg; 3.9-4.1 deg without the pads' stick state): a
pad turns the peg with its normal force at most half a contact length from the peg's middle
(5.5 mm here, 11 mm on the whole pad) while the pads' friction resists with mu = 1 at the peg's
radius (15 mm). Assemblies succeeded 4/4 up to 3 deg, 3/4 at 4 deg and 0/4 from 5.6 deg
(mostly ``timeout:insert``): the peg then stands tilted across the pinch axis, out of the plane
the search and the wiggle tilt in. See docs/training.md, "Jaw misalignment".
"""

from __future__ import annotations

import argparse
import math
from collections import Counter
from dataclasses import replace
from unittest import mock

import numpy as np

import vgs.assembly.episode as episode_mod
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.grasp import grasp
from vgs.cli.options import config_from_args


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--angles", default="0,2,4,5.6,8,11.25",
                    help="jaw misalignments to try [deg], comma-separated")
    ap.add_argument("--episodes", type=int, default=4, help="scenes per angle (seeds 0 ..)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)
    cfg = config_from_args(argparse.Namespace(profile="paper", set=args.set))  # as vgs does
    runner = EpisodeRunner(cfg)
    yaw_after: list[float] = []

    def watched_grasp(robot, x, y, yaw, surface):  # the primitive, then the peg's yaw in it
        result = grasp(robot, x, y, yaw, surface)
        _, R_world_peg = robot.cell.peg_pose()
        axis = R_world_peg[:2, 2] / np.linalg.norm(R_world_peg[:2, 2])
        cos = abs(float(axis @ np.array([math.cos(yaw), math.sin(yaw)])))
        yaw_after.append(math.degrees(math.acos(min(1.0, cos))))
        return result

    print(f"{'phi [deg]':>9}  {'yaw in pads after grasp [deg]':<30} {'assembled':>9} "
          f"{'mean time [s]':>13}  failures")
    centre = offset_policy(0.0)
    with mock.patch.object(episode_mod, "grasp", watched_grasp):
        for phi in (float(a) for a in args.angles.split(",")):
            def turned(hm, phi=phi):
                command = centre(hm)
                return replace(command, yaw=command.yaw + math.radians(phi))

            yaw_after.clear()
            records = [runner.run(seed, turned)[0] for seed in range(args.episodes)]
            ok = [r.assembly_time for r in records if r.success]
            fails = Counter(r.failure_reason for r in records if not r.success)
            yaws = ", ".join(f"{y:.1f}" for y in yaw_after)
            mean = f"{np.mean(ok):.1f}" if ok else "-"
            print(f"{phi:9.2f}  {yaws:<30} {len(ok):>4}/{len(records):<4} {mean:>13}  "
                  + (", ".join(f"{k} x{v}" for k, v in sorted(fails.items())) or "-"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
