"""How far from the peg's axis a policy's jaws closed in its tests, and what that did to the
assemblies (issue 18: why learned `paper-light` policies assemble a fraction of their tests).
An analysis probe of an evaluation's journal; figures only.

For each test episode of an evaluation folder (``journal.jsonl``; a finished one or one still
running), or each greedy episode of a training run (``episodes.csv``, ``--last N`` for the
latest; a baseline trained without assembly has none assembled), the scene is reset from the
episode's seed (as :meth:`EpisodeRunner.run` does) and the peg's yaw read from the simulator
(ground truth, for analysis only); the pads' long side lies along ``pads_heading(theta_k)``
for the executed rotation k (as ``pixel_command``). The jaw misalignment is the angle between
the two, folded into [0, 90] deg (the grasp is symmetric under a half turn). With R rotations a
policy can always come within ``180 / R`` deg (11.25 at R = 16). Printed per misalignment bin
and per folder: episodes, grasps held, assemblies.

Run: ``.venv/bin/python benchmarks/probe_policy_jaw_angle.py
runs/paper_light_s0/eval/vgs/s0/nominal runs/paper_light_s0/eval/baseline/s0/nominal``
(``--profile`` the run's profile, paper-light by default; nominal-peg conditions only: the
scene's peg pose does not depend on its mass, but other lengths are other cells).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from vgs.assembly.episode import EpisodeRunner
from vgs.config import profile
from vgs.experiments.journal import read_journal
from vgs.experiments.policies import pads_heading
from vgs.grasping.actions import rotation_angle

BINS = [0.0, 2.0, 4.0, 6.0, 8.0, 11.25, 90.0]


def folder_rows(folder: Path, last: int | None) -> list[dict]:
    """The test episodes of an evaluation folder (``journal.jsonl``), or the greedy episodes of
    a training run (``episodes.csv``, rows not explored; the last ``last`` of them if given)."""
    # A finished test folder also holds an episodes.csv, without the training column `explored`.
    if not (folder / "journal.jsonl").exists():
        table = pd.read_csv(folder / "episodes.csv")
        table = table[~table.explored.astype(bool)]
        rows = table.tail(last).to_dict("records") if last else table.to_dict("records")
    else:
        journal, _ = read_journal(folder / "journal.jsonl")
        rows = [r for r in journal.values() if "rotation" in r]
    if not rows:
        raise SystemExit(f"{folder}: no greedy training episodes or test episodes to read")
    return rows


def misalignment_deg(runner: EpisodeRunner, seed: int, rotation: int, rotations: int) -> float:
    """Angle [deg] in [0, 90] between the pads' long side for ``rotation`` and the true axis of
    the peg in the scene of ``seed``."""
    cell, _ = runner.cell(runner.cfg.cell.peg)
    cell.reset(np.random.default_rng(seed))
    _, R_world_peg = cell.peg_pose()
    peg_yaw = math.atan2(R_world_peg[1, 2], R_world_peg[0, 2])
    pads_yaw = pads_heading(rotation_angle(rotation, rotations))
    return abs((math.degrees(pads_yaw - peg_yaw) + 90.0) % 180.0 - 90.0)


def misalignments(folder: Path, runner: EpisodeRunner, rotations: int,
                  last: int | None = None) -> pd.DataFrame:
    """One row per episode: misalignment [deg], grasp held, assembled."""
    return pd.DataFrame([
        {"misalignment_deg": misalignment_deg(runner, int(r["seed"]), int(r["rotation"]),
                                              rotations),
         "held": bool(r["grasp_success"]), "assembled": str(r["assembly_success"]) == "True"}
        for r in folder_rows(folder, last)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path,
                        help="evaluation folders or training run folders")
    parser.add_argument("--last", type=int, default=None,
                        help="a training run's last N greedy episodes only")
    parser.add_argument("--profile", default="paper-light")
    args = parser.parse_args()
    cfg = profile(args.profile)
    runner = EpisodeRunner(cfg)
    rotations = cfg.network.num_rotations
    print(f"R = {rotations}: the nearest rotation lies within {180 / rotations:.2f} deg")
    for folder in args.folders:
        df = misalignments(folder, runner, rotations, args.last)
        df["bin"] = pd.cut(df.misalignment_deg, BINS, include_lowest=True)
        table = df.groupby("bin", observed=True).agg(
            episodes=("assembled", "size"), held=("held", "mean"),
            assembled=("assembled", "mean"))
        within = (df.misalignment_deg <= 180 / rotations).mean()
        print(f"\n{folder}: {len(df)} episodes, misalignment median "
              f"{df.misalignment_deg.median():.1f} deg, {within:.0%} within "
              f"{180 / rotations:.2f} deg; assembled {df.assembled.mean():.0%}")
        print(table.round(2).to_string())


if __name__ == "__main__":
    main()
