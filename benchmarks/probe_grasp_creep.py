"""Does the friction grasp creep under a steady moment below its capacity, with and without a
second contact on the peg? (An analysis probe of the cell's physics; figures only.)

The robot grasps the peg of one scene, turns it upright (the assembly's transport) and, with
``--where contact``, makes the approach's plane contact (the lower rim pressed on the table with
5 N). A moment of ``--fraction`` of the grasp's capacity (:func:`vgs.sim.rg2.grasp_moment_capacity`)
about the pinch axis is then applied to the peg as a step and held; the probe prints the peg's
turn in the pads (about the pinch axis, from the start of the load) every ``--every`` seconds::

    python benchmarks/probe_grasp_creep.py --where contact --fraction 0.33
    python benchmarks/probe_grasp_creep.py --where air --set cell.sim.noslip_iterations=10

What it showed on 2026-12-02 (seed 5, centre grasp, a third of the capacity, 5 s): with the pads'
stick state (:mod:`vgs.sim.stiction`, the default) 0.004 deg in free air and 0.117 deg with the
rim on the table (all of it in the first second); without it (``--set
cell.gripper.stiction=False``) 0.000 deg in free air and 1.1 deg on the table, still creeping;
with 10 no-slip iterations and no stick state the step turns the peg 34 deg in free air. See
docs/cell.md, "The grasp".
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.grasp import grasp
from vgs.assembly.strategy import AssemblyModule
from vgs.cli.options import config_from_args
from vgs.control.robot import Robot
from vgs.sim.rg2 import grasp_moment_capacity


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--where", choices=("air", "contact"), default="contact")
    ap.add_argument("--fraction", type=float, default=0.33, help="of the grasp's capacity")
    ap.add_argument("--offset-mm", type=float, default=0.0, help="grasp offset from the centre")
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--every", type=float, default=0.5)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)

    cfg = config_from_args(argparse.Namespace(profile="paper", set=args.set))  # as vgs does
    runner = EpisodeRunner(cfg)
    cell, cam = runner.cell(cfg.cell.peg)
    cell.reset(np.random.default_rng(args.seed))
    hm = cam.capture(cell.data)
    robot = Robot(cell, cfg.controller, np.random.default_rng([args.seed, 1]))
    command = offset_policy(args.offset_mm / 1000.0)(hm)
    row, col = hm.world_to_pixel(command.x, command.y)
    robot.run(0.2)
    robot.arm.tare()
    if not grasp(robot, command.x, command.y, command.yaw, float(hm.depth[row, col])).success:
        raise SystemExit("the grasp failed on this scene; try another --seed")
    hole = cfg.cell.hole
    module = AssemblyModule(robot, cfg.assembly, cfg.cell.peg, hole.nominal_xy, hole.depth,
                            hole.clearance)
    module._begin("transport")
    module.transport()
    if args.where == "contact":
        module._begin("approach")
        module.approach()
    robot.run(0.5)

    d, ids = cell.data, cell.ids

    def turn() -> float:
        R_world_tcp = d.site_xmat[ids.tcp_site].reshape(3, 3)
        axis_tcp = R_world_tcp.T @ d.xmat[ids.peg_body].reshape(3, 3)[:, 2]
        return math.degrees(math.atan2(axis_tcp[2], abs(axis_tcp[0])))

    capacity = grasp_moment_capacity(cell.cfg.gripper)
    moment = args.fraction * capacity
    print(f"capacity {capacity:.3f} N m; step moment {moment:.3f} N m about the pinch axis; "
          f"peg {'in plane contact' if args.where == 'contact' else 'in free air'}; "
          f"noslip_iterations {cell.model.opt.noslip_iterations}")
    start, n_every = turn(), max(1, int(round(args.every / robot.dt)))
    for k in range(1, int(round(args.seconds / robot.dt)) + 1):
        pinch = d.site_xmat[ids.tcp_site].reshape(3, 3)[:, 1]
        d.xfrc_applied[ids.peg_body, 3:] = moment * pinch
        robot.tick()
        if k % n_every == 0 or k == 10:
            print(f"t {k * robot.dt:5.2f} s  turn in the pads {turn() - start:+8.3f} deg  "
                  f"F_z {robot.arm.wrench[2]:+6.2f} N")
    d.xfrc_applied[ids.peg_body] = 0.0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
