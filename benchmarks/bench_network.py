"""Time one grasp decision and one training step of the grasp Q network.

A *decision* is :meth:`GraspAgent.act` with epsilon = 0 on a size x size heightmap: preprocessing,
one batched eval-mode forward pass of all R rotations (one map for the position action) under
``torch.inference_mode`` and the masked argmax. A *training step* is :meth:`GraspAgent.update` on a
terminal transition (y = r): a train-mode forward pass of the executed rotation and its opposite,
the Huber loss at the executed pixel, backward and one SGD step. Each is timed ``--repeats`` times
after ``--warmup`` untimed calls; the median wall-clock time is printed, with the median process
CPU time (all threads) beside it, and the load average before and after (on a shared machine other
processes inflate the wall-clock times).

Usage::

    python benchmarks/bench_network.py [--backbones densenet121 light] [--rotations 16]
        [--action rotation|position] [--device cpu|cuda] [--rotate input features]
        [--memory-format contiguous channels_last]
        [--precision float32 bfloat16] [--threads N] [--size 224] [--repeats 3] [--warmup 1]
        [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch

from vgs.config import ACTIONS, BACKBONES, PRECISIONS, AgentConfig, NetworkConfig
from vgs.grasping.agent import GraspAgent
from vgs.grasping.network import ROTATE_MODES
from vgs.grasping.replay import Transition

MEMORY_FORMATS = ("contiguous", "channels_last")


def _scene(size: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A heightmap with one lying peg (a bar 3 cm tall), its colour map and its mask."""
    rng = np.random.default_rng(seed)
    color = rng.integers(30, 60, (size, size, 3), dtype=np.uint8)
    depth = np.zeros((size, size), np.float32)
    r0, c0 = size // 2 - size // 16, size // 2 - size // 4
    depth[r0:r0 + size // 8, c0:c0 + size // 2] = 0.03
    color[depth > 0] = (200, 200, 200)
    return color, depth, depth > 0.005


def _time(
    fn: Callable[[], Any], repeats: int, warmup: int, device: torch.device
) -> tuple[list[float], list[float]]:
    """Wall-clock and process-CPU seconds of each timed call."""
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(repeats):
        if device.type == "cuda":
            torch.cuda.synchronize(device)
        start, start_cpu = time.perf_counter(), time.process_time()
        fn()
        if device.type == "cuda":
            torch.cuda.synchronize(device)
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return wall, cpu


def _load() -> str:
    """1, 5 and 15 minute load averages (other processes on the machine skew the timings)."""
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "n/a"


def bench_one(
    backbone: str,
    rotate: str,
    memory_format: str,
    rotations: int,
    size: int,
    device: str,
    repeats: int,
    warmup: int,
    precision: str = "float32",
    action: str = "rotation",
) -> dict[str, Any]:
    """Decision and training-step times of one configuration [s]."""
    agent = GraspAgent(
        NetworkConfig(action=action, backbone=backbone, num_rotations=rotations,
                      precision=precision),
        AgentConfig(),
        device=device,
        rotate=rotate,
        channels_last=memory_format == "channels_last",
    )
    color, depth, mask = _scene(size)
    rng = np.random.default_rng(0)
    dev = torch.device(device)
    decide, decide_cpu = _time(lambda: agent.act(color, depth, 0.0, mask, rng), repeats, warmup,
                               dev)
    row, col = (int(v) for v in np.argwhere(mask)[0])
    k = min(1, agent.network_cfg.q_maps - 1)  # a rotation with an opposite one where R > 1
    transition = Transition(color, depth, (k, row, col), 1.0)
    train, train_cpu = _time(lambda: agent.update(transition), repeats, warmup, dev)
    return {
        "backbone": backbone,
        "action": action,
        "rotate": rotate,
        "memory_format": memory_format,
        "precision": precision,
        "rotations": rotations,
        "size": size,
        "device": device,
        "threads": torch.get_num_threads(),
        "decision_s": statistics.median(decide),
        "decision_range_s": [min(decide), max(decide)],
        "decision_cpu_s": statistics.median(decide_cpu),
        "train_step_s": statistics.median(train),
        "train_step_range_s": [min(train), max(train)],
        "train_step_cpu_s": statistics.median(train_cpu),
        "repeats": repeats,
    }


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    """Parse the arguments, run every configuration and print one line per configuration."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backbones", nargs="+", choices=BACKBONES, default=list(BACKBONES))
    parser.add_argument("--rotations", type=int, default=16)
    parser.add_argument("--action", choices=ACTIONS, default="rotation",
                        help="network.action (default: rotation, whose R maps the figures of "
                             "docs/grasping.md time); rotate modes it does not take are skipped")
    parser.add_argument("--device", choices=("cpu", "cuda"), default="cpu")
    parser.add_argument("--rotate", nargs="+", choices=ROTATE_MODES, default=list(ROTATE_MODES))
    parser.add_argument("--memory-format", nargs="+", choices=MEMORY_FORMATS,
                        default=list(MEMORY_FORMATS))
    parser.add_argument("--precision", nargs="+", choices=PRECISIONS, default=["float32"],
                        help="network.precision values to time (default: float32)")
    parser.add_argument("--threads", type=int, default=None,
                        help="torch.set_num_threads (default: leave torch's choice)")
    parser.add_argument("--size", type=int, default=224)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--warmup", type=int, default=1)
    parser.add_argument("--json", type=Path, default=None, help="also write the results here")
    args = parser.parse_args(argv)
    if args.threads is not None:
        torch.set_num_threads(args.threads)
    if args.device == "cuda" and not torch.cuda.is_available():
        parser.error("--device cuda: no CUDA device available")
    print(f"torch {torch.__version__}, {platform.processor() or platform.machine()}, "
          f"device {args.device}, threads {torch.get_num_threads()}, "
          f"heightmap {args.size}x{args.size}, {args.action} action, R = {args.rotations}, "
          f"median of {args.repeats} "
          f"after {args.warmup} warm-up")
    print(f"load average before: {_load()}")
    header = (f"{'backbone':<12} {'rotate':<9} {'memory':<14} {'precision':<9} {'threads':>7} "
              f"{'decision [s]':>13} {'(cpu [s])':>10} {'train step [s]':>15} {'(cpu [s])':>10}")
    print(header)
    print("-" * len(header))
    results = []
    for backbone in args.backbones:
        for rotate in args.rotate:
            if rotate not in (("input", "none") if args.action == "position"
                              else ("input", "features")):
                continue
            for memory_format in args.memory_format:
                for precision in args.precision:
                    r = bench_one(backbone, rotate, memory_format, args.rotations, args.size,
                                  args.device, args.repeats, args.warmup, precision,
                                  args.action)
                    results.append(r)
                    print(f"{backbone:<12} {rotate:<9} {memory_format:<14} {precision:<9} "
                          f"{r['threads']:>7} {r['decision_s']:>13.3f} "
                          f"{r['decision_cpu_s']:>10.3f} {r['train_step_s']:>15.3f} "
                          f"{r['train_step_cpu_s']:>10.3f}", flush=True)
    print(f"load average after: {_load()}")
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=2))
    return results


if __name__ == "__main__":
    main()
