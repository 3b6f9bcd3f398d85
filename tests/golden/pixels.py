"""A trained network's chosen pixels under every PyTorch CPU capability (issue 51, item 3).

The network is the one part of an episode that keeps vectorised kernels (PyTorch's and
oneDNN's, chosen per CPU and by ``ATEN_CPU_CAPABILITY``): its Q values differ in their last
bits between capabilities, by several bfloat16 steps where the CPU has no bfloat16 units, so a
pixel can flip where two pixels' Q values are that close. This script computes the greedy
decision of a published policy on the first ``--scenes`` nominal test scenes of its recorded
configuration under each capability (one subprocess each) and prints on how many scenes the
pixel agrees, and whether every flip is a near tie: the other capability's pixel lies within
``TIE_Q`` (8 bfloat16 steps at Q = 1) of the chosen one's Q in the same map:

    .venv/bin/python tests/golden/pixels.py --policy docs/results/paper_light_s0/vgs --scenes 200

``tests/test_kernels.py`` runs it on a few scenes. Measured: 200 of 200 the same on an Intel
Xeon with AVX-512; 39 of 40 on an AMD EPYC with AVX2 alone (one near tie).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

CAPABILITIES = ("default", "avx2", "avx512")
TIE_Q = 8 * 2.0 ** -8  # 8 bfloat16 steps of a Q value in [0.5, 1)
TOP = 200  # the highest pixels of each map kept to judge a flip


def decide(policy_dir: str, scenes: int) -> list[dict[str, list[float]]]:
    """The greedy decision (row, col, rotation, q) on each scene and its map's ``TOP`` highest
    allowed pixels (rotation, row, col, q), in this process."""
    import numpy as np

    from vgs.assembly.episode import EpisodeRunner
    from vgs.config.conditions import eval_scenes
    from vgs.grasping.actions import peg_mask
    from vgs.rollout.policies import GreedyPolicy

    policy = GreedyPolicy(Path(policy_dir))
    cfg = policy.run_config
    runner = EpisodeRunner(cfg)
    out = []
    seed = cfg.reproduce.eval_seed  # the test scenes of the run's reproduction
    for scene in eval_scenes(cfg.cell.peg, cfg.eval, "nominal", seed, scenes):
        hm = runner.observe(scene.seed, scene.peg)
        d = policy(hm, np.random.default_rng(scene.seed))
        q = np.where(peg_mask(hm.depth)[None], policy.agent.q_values(hm.color, hm.depth),
                     -np.inf)
        top = np.argsort(q, axis=None, kind="stable")[::-1][:TOP]
        out.append({"chosen": [d.row, d.col, d.rotation, d.q_value],
                    "top": [[*map(int, np.unravel_index(t, q.shape)), float(q.flat[t])]
                            for t in top if np.isfinite(q.flat[t])]})
    return out


def _gap(result: dict[str, list], row: int, col: int, rotation: int) -> float:
    """How far below its chosen pixel's Q one map puts the pixel (row, col, rotation); inf
    when the pixel is not among its ``TOP``."""
    for k, i, j, q in result["top"]:
        if (i, j, k) == (row, col, rotation):
            return float(result["chosen"][3] - q)
    return float("inf")


def compare(policy_dir: str, scenes: int, capabilities: tuple[str, ...]
            ) -> tuple[int, int, int, str]:
    """(scenes whose pixel agrees under every capability, scenes whose pixels differ by a near
    tie, scenes, a report line)."""
    results = {}
    for cap in capabilities:
        env = dict(os.environ, ATEN_CPU_CAPABILITY=cap, OPENBLAS_NUM_THREADS="1")
        proc = subprocess.run([sys.executable, __file__, "--policy", policy_dir, "--scenes",
                               str(scenes), "--worker"], env=env, capture_output=True,
                              text=True, check=False)
        if proc.returncode != 0:
            raise SystemExit(f"ATEN_CPU_CAPABILITY={cap}: {proc.stderr.strip()[-500:]}")
        results[cap] = json.loads(proc.stdout)
    same = ties = 0
    worst = 0.0
    for i in range(scenes):
        picks = {c: tuple(results[c][i]["chosen"][:3]) for c in capabilities}
        if len(set(picks.values())) == 1:
            same += 1
            continue
        gap = max(_gap(results[c][i], *picks[o]) for c in capabilities for o in capabilities)
        worst = max(worst, gap)
        ties += gap <= TIE_Q
    dq = max(abs(results[c][i]["chosen"][3] - results[capabilities[0]][i]["chosen"][3])
             for c in capabilities for i in range(scenes))
    line = (f"{scenes - same} flip, {ties} of them near ties (largest Q gap between the two "
            f"pixels in one map {worst:.2e}, a tie is <= {TIE_Q:.2e}); largest difference of "
            f"the chosen Q between capabilities {dq:.2e}")
    return same, ties, scenes, line


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy", required=True, help="a published policy or training run")
    parser.add_argument("--scenes", type=int, default=200)
    parser.add_argument("--capabilities", default=",".join(CAPABILITIES))
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(decide(args.policy, args.scenes)))
        return
    caps = tuple(c for c in args.capabilities.split(",") if c)
    same, _, total, line = compare(args.policy, args.scenes, caps)
    print(f"{args.policy}: the same pixel under {', '.join(caps)} on {same} of {total} "
          f"scenes; {line}")


if __name__ == "__main__":
    main()
