"""Every benchmark runs, at a tiny size, so that none rots (issue 40, item 4).

``benchmarks/`` holds benchmarks only: ``bench_*.py`` (each run here in a subprocess with the
arguments below, about 1 min together on a loaded 2-core host), ``bench_gpu_node.sh`` and
``bench_fresh_clone.sh`` (checked for syntax only: one needs a GPU node, the other a clone, a
set-up and the quick profile's run). Figures are not checked, only that each script
finishes and prints its last section.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"

# script -> (tiny arguments, a line fragment its last section prints)
TINY: dict[str, tuple[list[str], str]] = {
    "bench_cell.py": (["--profile", "smoke", "--episodes", "1", "--steps", "20"],
                      "under OPENBLAS_CORETYPE"),
    "bench_eval.py": (["--episodes", "1", "--no-ray", "--light-episodes", "0",
                       "--probe-steps", "200"], "quick profile: not measured"),
    "bench_network.py": (["--backbones", "light", "--rotations", "2", "--rotate", "input",
                          "features", "--memory-format", "contiguous", "--size", "32",
                          "--repeats", "1", "--warmup", "0"], "load average after"),
    "bench_replay.py": (["--scenes", "2", "--steps", "1", "--threads", "1"],
                        "checkpoint (scenes)"),
    "bench_maskable_ppo.py": (["--steps", "4", "--block", "2", "--eval", "1", "--no-unmasked",
                               "--n-steps", "4"], "evaluation, 1 fresh scenes"),
    "bench_train.py": (["--episodes", "0", "--no-ray", "--backbone", "light"],
                       "limit (the learner alone)"),
}


def test_benchmarks_holds_benchmarks_only() -> None:
    names = {p.name for p in BENCHMARKS.iterdir() if not p.name.startswith((".", "__"))}
    assert names == {*TINY, "bench_gpu_node.sh", "bench_fresh_clone.sh"}


@pytest.mark.parametrize("script", sorted(TINY))
def test_benchmark_runs_at_a_tiny_size(script: str) -> None:
    args, last = TINY[script]
    result = subprocess.run([sys.executable, str(BENCHMARKS / script), *args],
                            capture_output=True, text=True, timeout=600, cwd=BENCHMARKS.parent)
    assert result.returncode == 0, result.stderr[-3000:]
    assert last in result.stdout, result.stdout[-3000:]


@pytest.mark.parametrize("script", ["bench_gpu_node.sh", "bench_fresh_clone.sh"])
def test_shell_benchmark_parses(script: str) -> None:
    result = subprocess.run(["bash", "-n", str(BENCHMARKS / script)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
