"""A trained network's chosen pixels under every PyTorch CPU capability (issue 51, item 3).

The network is the one part of an episode that keeps vectorised kernels (PyTorch's, chosen per
CPU by ``ATEN_CPU_CAPABILITY``): its Q values may differ in their last bits between
capabilities, so what must not move is the pixel it picks. This script computes the greedy
decision of a published policy on the first ``--scenes`` nominal test scenes of its recorded
configuration under each capability (one subprocess each) and prints how many pixels agree and
the smallest Q gap between the chosen pixel and the runner-up among those that flip:

    .venv/bin/python tests/golden/pixels.py --policy docs/results/paper_light_s0/vgs --scenes 200

``tests/test_kernels.py`` runs it on a few scenes.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

CAPABILITIES = ("default", "avx2", "avx512")


def decide(policy_dir: str, scenes: int) -> list[list[float]]:
    """(row, col, rotation, q) of the greedy decision on each scene, in this process."""
    import numpy as np

    from vgs.assembly.episode import EpisodeRunner
    from vgs.config.conditions import eval_scenes
    from vgs.rollout.policies import GreedyPolicy

    policy = GreedyPolicy(Path(policy_dir))
    cfg = policy.run_config
    runner = EpisodeRunner(cfg)
    out = []
    seed = cfg.reproduce.eval_seed  # the test scenes of the run's reproduction
    for scene in eval_scenes(cfg.cell.peg, cfg.eval, "nominal", seed, scenes):
        hm = runner.observe(scene.seed, scene.peg)
        d = policy(hm, np.random.default_rng(scene.seed))
        out.append([d.row, d.col, d.rotation, d.q_value])
    return out


def compare(policy_dir: str, scenes: int, capabilities: tuple[str, ...]) -> tuple[int, int, str]:
    """(scenes whose pixel agrees under every capability, scenes, a report line each)."""
    results = {}
    for cap in capabilities:
        env = dict(os.environ, ATEN_CPU_CAPABILITY=cap, OPENBLAS_NUM_THREADS="1")
        proc = subprocess.run([sys.executable, __file__, "--policy", policy_dir, "--scenes",
                               str(scenes), "--worker"], env=env, capture_output=True,
                              text=True, check=False)
        if proc.returncode != 0:
            raise SystemExit(f"ATEN_CPU_CAPABILITY={cap}: {proc.stderr.strip()[-500:]}")
        results[cap] = json.loads(proc.stdout)
    first = results[capabilities[0]]
    same = sum(all(results[c][i][:3] == first[i][:3] for c in capabilities)
               for i in range(scenes))
    dq = max(abs(results[c][i][3] - first[i][3]) for c in capabilities for i in range(scenes))
    lines = f"largest Q difference between capabilities: {dq:.2e}"
    return same, scenes, lines


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
    same, total, line = compare(args.policy, args.scenes, caps)
    print(f"{args.policy}: the same pixel under {', '.join(caps)} on {same} of {total} "
          f"scenes; {line}")


if __name__ == "__main__":
    main()
