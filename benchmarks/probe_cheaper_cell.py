"""What cheaper physics settings would buy, and what they would cost the cell as an instrument
(issue 18, item 1: the `paper-light` protocol's 2.5 h). An analysis probe; figures only.

Runs the same episodes (scene seeds x grasp offsets along the peg's visible axis, as
``offset_policy``) on the `paper-light` profile's cell and on variants of it, interleaved so
that every variant sees the same load on the host, and prints per variant:

* the CPU seconds per episode (this process's CPU time: what an idle core would take) and its
  ratio to the unchanged cell, the figure item 1 needs about 1.7x of;
* the real-time factor (simulated seconds / CPU seconds);
* assemblies that succeeded (with a 95 % Wilson interval), their mean time and alignment time,
  the re-searches (``retries``) and the failures, all on the same scenes as the unchanged cell.

Variants (``--variants``, comma-separated; each a set of ``--set``-style overrides):

* ``base``: the cell as published (2 ms step, controller at 100 Hz, 32 hole wedges);
* ``ctl50``: the controller at 50 Hz (``cell.sim.control_decimation=10``), half the Python per
  simulated second;
* ``dt2.5``: a 2.5 ms step (``cell.sim.timestep=0.0025``, ``control_decimation=4``, contact
  time constant 5 ms, the smallest the step allows);
* ``seg16``: a hole of 16 wedges instead of 32 (half the narrow-phase pairs; the inner surface
  within 0.3 mm of the circle instead of 0.08 mm);
* ``combo``: ``dt2.5`` with the controller at 50 Hz (``control_decimation=8``).

Run: ``.venv/bin/python benchmarks/probe_cheaper_cell.py --variants base,ctl50,dt2.5,seg16
--scenes 1000:1030`` (``--offsets-mm -35,0,35`` by default).
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.config import ExperimentConfig, override, profile
from vgs.experiments.sweepstats import wilson_interval
from vgs.runfolder import host

# Overrides in the order they are applied (a time step's validation reads the time constant).
VARIANTS: dict[str, tuple[tuple[str, Any], ...]] = {
    "base": (),
    "ctl50": (("cell.sim.control_decimation", 10),),
    "dt2.5": (("cell.sim.control_decimation", 4), ("cell.sim.contact_timeconst", 0.005),
              ("cell.sim.timestep", 0.0025)),
    "seg16": (("cell.hole.segments", 16),),
    "combo": (("cell.sim.control_decimation", 8), ("cell.sim.contact_timeconst", 0.005),
              ("cell.sim.timestep", 0.0025)),
}


def variant_config(name: str, base: ExperimentConfig) -> ExperimentConfig:
    """The profile with the variant's overrides applied."""
    cfg = base
    for key, value in VARIANTS[name]:
        cfg = override(cfg, key, value)
    return cfg


def run(names: list[str], scenes: range, offsets_mm: list[float]) -> dict[str, list[dict]]:
    """Every (scene, offset) episode on every variant, interleaved; one row per episode."""
    base = profile("paper-light")
    runners = {name: EpisodeRunner(variant_config(name, base)) for name in names}
    rows: dict[str, list[dict]] = {name: [] for name in names}
    total = len(scenes) * len(offsets_mm)
    for k, (seed, off) in enumerate((s, o) for s in scenes for o in offsets_mm):
        for name, runner in runners.items():
            c0 = time.process_time()
            record, robot, _ = runner.run(seed, offset_policy(off / 1000))
            rows[name].append({"cpu": time.process_time() - c0, "sim": robot.time,
                               "ok": record.success, "why": record.failure_reason,
                               "time": record.assembly_time,
                               "align": record.phase_times["align"],
                               "retries": record.retries})
        print(f"\r{k + 1}/{total} episodes per variant", end="", flush=True)
    print()
    return rows


def report(rows: dict[str, list[dict]]) -> None:
    """Print one line per variant (CPU ratio against the first variant)."""
    ref = statistics.mean(r["cpu"] for r in next(iter(rows.values())))
    print(f"{'variant':8s} {'CPU s/ep':>8s} {'ratio':>6s} {'RTF':>5s} {'assembled':>17s} "
          f"{'mean s':>6s} {'align s':>7s} {'re-search':>9s}  failures")
    for name, rs in rows.items():
        n, ok = len(rs), [r for r in rs if r["ok"]]
        cpu = statistics.mean(r["cpu"] for r in rs)
        rtf = sum(r["sim"] for r in rs) / sum(r["cpu"] for r in rs)
        lo, hi = wilson_interval(len(ok), n)
        mean_t = statistics.mean(r["time"] for r in ok) if ok else float("nan")
        align = statistics.mean(r["align"] for r in ok) if ok else float("nan")
        fails = ", ".join(r["why"] for r in rs if not r["ok"]) or "-"
        print(f"{name:8s} {cpu:8.2f} {ref / cpu:6.2f} {rtf:5.1f} "
              f"{len(ok):3d}/{n:<3d} [{lo:.2f},{hi:.2f}] {mean_t:6.1f} {align:7.1f} "
              f"{sum(r['retries'] for r in rs):9d}  {fails}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--variants", default="base,ctl50,dt2.5,seg16,combo",
                        help=f"comma-separated, from {', '.join(VARIANTS)}; the first is the "
                             "reference of the CPU ratio")
    parser.add_argument("--scenes", default="1000:1030", help="scene seeds FIRST:END")
    parser.add_argument("--offsets-mm", default="-35,0,35",
                        help="grasp offsets from the visible centre [mm]")
    args = parser.parse_args()
    names = args.variants.split(",")
    unknown = [n for n in names if n not in VARIANTS]
    if unknown:
        parser.error(f"unknown variants {unknown}; choose from {list(VARIANTS)}")
    first, _, end = args.scenes.partition(":")
    scenes = range(int(first), int(end))
    offsets = [float(x) for x in args.offsets_mm.split(",")]
    where = host()
    print(f"host: {where['host_cpu']}, MuJoCo {where['mujoco_version']}; paired episodes: "
          f"{len(scenes)} scenes x offsets {offsets} mm")
    report(run(names, scenes, offsets))


if __name__ == "__main__":
    main()
