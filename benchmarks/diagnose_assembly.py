"""Where the assembly loses its peg: per phase, the contact force's chatter and the peg's turn in
the pads, from ground truth recorded per tick (an analysis probe; the controller never sees it).

For each grasp offset and scene it runs one whole episode with ``trace=True`` and replays the
recorded states through MuJoCo's kinematics to get, per phase:

* ``Fz`` mean and standard deviation of the measured vertical contact force [N] (the press
  force is the target: a large deviation is stick-slip or bouncing);
* the peg's turn in the pads [deg]: the growth over the phase of the angle between the peg's
  axis in the tool frame and its axis at the start of the assembly;
* the peg's tilt from vertical at the end of the phase [deg] (the search tilts it by
  ``assembly.search_tilt_deg``; what the pads lose of it the controller does not know).

Usage (2 workers, scenes paired across offsets as in ``vgs sweep``)::

    python benchmarks/diagnose_assembly.py --scenes 4 --offsets-mm 0
    python benchmarks/diagnose_assembly.py --scenes 4 --offsets-mm 0 \
        --set assembly.search_stiffness=20000

``--set`` takes ``key=value`` pairs like the CLI (values are Python literals).

``--trace OFFSET_MM SCENE`` prints one episode's timeline instead, every ``--every`` seconds
of each phase: the distance of the peg's lower face centre from the hole's axis, the depth of
its lowest rim point below the hole's top face, its tilt from vertical and the measured force::

    python benchmarks/diagnose_assembly.py --trace 0 5 --every 0.25
"""

from __future__ import annotations

import argparse
import ast
import collections
import math
import multiprocessing as mp
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

PHASES = ("transport", "approach", "search", "slide", "align", "insert")


@dataclass
class PhaseStats:
    """Per-phase signals of one episode."""

    fz: list[float] = field(default_factory=list)
    turn_deg: float = 0.0  # net growth of the peg's turn in the pads, summed over visits
    tilt_end_deg: float = math.nan  # peg tilt from vertical at the phase's last tick
    duration: float = 0.0


@dataclass
class EpisodeDiagnosis:
    offset_mm: float
    scene: int
    success: bool
    failure: str
    retries: int
    peak_grasp_moment: float
    phases: dict[str, PhaseStats]
    time: float = math.nan  # assembly time [s]
    sequence: str = ""  # the phases in the order they ran, e.g. "search slide search slide ..."


_RUNNER = None


def _init(sets: list[tuple[str, object]]) -> None:
    global _RUNNER
    from vgs.assembly.episode import EpisodeRunner
    from vgs.config import override, profile

    cfg = profile("paper")
    for key, value in sets:
        cfg = override(cfg, key, value)
    _RUNNER = EpisodeRunner(cfg)


def _run_traced(offset_mm: float, scene: int, root: int) -> tuple[Any, Any]:
    """``(record, robot)`` of scene ``scene`` (seeded as ``vgs sweep`` seeds its trials) with
    the grasp ``offset_mm`` from the visible centre, per-tick states kept."""
    from vgs.assembly.episode import offset_policy

    seed = int(np.random.SeedSequence([root, scene]).generate_state(1)[0])
    record, robot, _ = _RUNNER.run(seed, offset_policy(offset_mm / 1000.0), trace=True)
    return record, robot


def _replay(robot: Any) -> Iterator[tuple[float, str, np.ndarray, Any]]:
    """``(time, phase, measured wrench, data)`` of each assembly tick, ``data`` holding the
    recorded state with MuJoCo's kinematics applied (poses only)."""
    trace, cell = robot.trace, robot.cell
    data = mujoco.MjData(cell.model)
    for t, phase, wrench, qpos in zip(trace.time, trace.phase, trace.wrench, trace.qpos,
                                      strict=True):
        if phase not in PHASES:
            continue
        data.qpos[:] = qpos
        mujoco.mj_kinematics(cell.model, data)
        yield t, phase, wrench, data


def _diagnose(job: tuple[float, int, int]) -> EpisodeDiagnosis:
    offset_mm, scene, root = job
    record, robot = _run_traced(offset_mm, scene, root)
    ids = robot.cell.ids
    phases: dict[str, PhaseStats] = {}
    axis0 = None
    visit_start = 0.0  # turn when the current visit of a phase began
    prev_phase, prev_time, prev_turn = None, 0.0, 0.0
    visits: list[str] = []
    for t, phase, wrench, data in _replay(robot):
        if not visits or visits[-1] != phase:
            visits.append(phase)
        R_world_tcp = data.site_xmat[ids.tcp_site].reshape(3, 3)
        peg_axis = data.xmat[ids.peg_body].reshape(3, 3)[:, 2]
        axis_tcp = R_world_tcp.T @ peg_axis
        if axis0 is None:
            axis0 = axis_tcp
        turn = math.degrees(math.acos(max(-1.0, min(1.0, float(np.dot(axis_tcp, axis0))))))
        if phase != prev_phase:
            if prev_phase is not None:  # close the previous visit: its net turn
                phases[prev_phase].turn_deg += prev_turn - visit_start
            visit_start, prev_time = turn, t
        stats = phases.setdefault(phase, PhaseStats())
        stats.fz.append(float(wrench[2]))
        stats.tilt_end_deg = math.degrees(math.acos(min(1.0, abs(float(peg_axis[2])))))
        stats.duration += t - prev_time
        prev_phase, prev_time, prev_turn = phase, t, turn
    if prev_phase is not None:
        phases[prev_phase].turn_deg += prev_turn - visit_start
    return EpisodeDiagnosis(offset_mm, scene, bool(record.success),
                            record.failure_reason or "", int(record.retries),
                            float(record.peak_grasp_moment), phases,
                            float(record.assembly_time), " ".join(visits[2:]))


def trace_episode(sets: list[tuple[str, object]], offset_mm: float, scene: int, root: int,
                  every: float) -> None:
    """Print the ground-truth timeline of one episode (see the module docstring)."""
    _init(sets)
    record, robot = _run_traced(offset_mm, scene, root)
    cell = robot.cell
    hole = cell.hole_position()
    half, radius = 0.5 * cell.cfg.peg.length, 0.5 * cell.cfg.peg.diameter
    print(f"hole {np.linalg.norm(cell.hole_xy - cell.cfg.hole.nominal_xy) * 1000:.1f} mm from "
          "nominal; columns: time [s], phase, lower face centre from the hole axis (x, y) [mm], "
          "lowest rim point below the hole's top face [mm], tilt [deg], measured force [N]")
    last_phase, last_t = None, -math.inf
    for t, phase, wrench, data in _replay(robot):
        if phase == last_phase and t - last_t < every:
            continue
        if phase != last_phase:
            print(f"-- {phase}")
        last_phase, last_t = phase, t
        p = data.xpos[cell.ids.peg_body]
        axis = data.xmat[cell.ids.peg_body].reshape(3, 3)[:, 2]
        down = -axis if axis[2] > 0 else axis  # from the centre to the lower face
        face = p + half * down
        v = np.array([0.0, 0.0, -1.0]) - down * float(-down[2])
        n = float(np.linalg.norm(v))
        rim = face + (radius * v / n if n > 1e-9 else 0.0)
        tilt = math.degrees(math.acos(min(1.0, abs(float(axis[2])))))
        d = (face[:2] - hole[:2]) * 1000
        print(f"{t:7.2f} {phase:9s} face ({d[0]:+6.1f}, {d[1]:+6.1f}) rim depth "
              f"{(hole[2] - rim[2]) * 1000:+6.2f} tilt {tilt:5.2f} F ({wrench[0]:+5.2f}, "
              f"{wrench[1]:+5.2f}, {wrench[2]:+6.2f})")
    print(f"assembled: {bool(record.success)} {record.failure_reason or ''} "
          f"time {record.assembly_time:.1f} s, retries {record.retries}")


def _parse_set(items: list[str]) -> list[tuple[str, object]]:
    sets = []
    for item in items:
        key, sep, text = item.partition("=")
        if not sep:
            raise SystemExit(f"--set needs key=value, got {item!r}")
        try:
            value: object = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            value = text
        sets.append((key, value))
    return sets


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=4)
    ap.add_argument("--offsets-mm", default="-35,0,35")
    ap.add_argument("--seed", type=int, default=7, help="root seed of the scenes")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--trace", nargs=2, type=float, metavar=("OFFSET_MM", "SCENE"))
    ap.add_argument("--every", type=float, default=0.25, help="trace period [s]")
    ap.add_argument("--episodes", action="store_true",
                    help="also print one line per episode (outcome, retries, turn per phase)")
    args = ap.parse_args(argv)
    sets = _parse_set(args.set)
    if args.trace is not None:
        trace_episode(sets, args.trace[0], int(args.trace[1]), args.seed, args.every)
        return 0
    offsets = [float(x) for x in args.offsets_mm.split(",")]
    jobs = [(o, s, args.seed) for s in range(args.scenes) for o in offsets]
    with mp.get_context("spawn").Pool(args.workers, initializer=_init, initargs=(sets,)) as pool:
        results = pool.map(_diagnose, jobs, chunksize=1)
    print("settings:", ", ".join(f"{k}={v}" for k, v in sets) or "defaults")
    if args.episodes:
        for r in results:
            turns = " ".join(f"{ph}:{st.turn_deg:+.1f}" for ph, st in r.phases.items()
                             if ph != "transport")
            print(f"  {r.offset_mm:+6.1f} mm scene {r.scene:3d} "
                  f"{'ok  ' if r.success else 'FAIL'} {r.failure:16s} retries {r.retries} "
                  f"time {r.time:5.1f} s peak {r.peak_grasp_moment:.2f} N m  turn {turns}")
            if r.retries:
                print(f"      phases: {r.sequence}")
    for offset in offsets:
        rows = [r for r in results if r.offset_mm == offset]
        fails = collections.Counter(r.failure for r in rows if not r.success)
        print(f"\noffset {offset:+.1f} mm: {sum(r.success for r in rows)}/{len(rows)} assembled, "
              f"retries {np.mean([r.retries for r in rows]):.2f} per episode, "
              f"peak grasp moment median {np.median([r.peak_grasp_moment for r in rows]):.3f} "
              f"N m, failures {dict(fails)}")
        times = np.array([r.time for r in rows if r.success])
        if len(times) > 1:
            print(f"  assembled: time {times.mean():.1f} s, sd {times.std(ddof=1):.1f} s, "
                  f"CV {times.std(ddof=1) / times.mean():.2f}; re-search in "
                  f"{sum(r.retries > 0 for r in rows)}/{len(rows)} episodes")
        print(f"  {'phase':9s} {'time [s]':>9s} {'sd [s]':>6s} {'Fz [N]':>7s} {'Fz sd':>6s} "
              f"{'turn mean':>9s} {'turn max':>8s} {'tilt end':>8s}")
        for phase in PHASES:
            have = [r.phases[phase] for r in rows if phase in r.phases]
            if not have:
                continue
            fz = np.concatenate([np.asarray(p.fz) for p in have])
            sd = np.mean([np.std(p.fz) for p in have])
            turns = [p.turn_deg for p in have]
            durations = [p.duration for p in have]
            print(f"  {phase:9s} {np.mean(durations):9.1f} {np.std(durations):6.1f} "
                  f"{fz.mean():7.2f} "
                  f"{sd:6.2f} {np.mean(turns):9.2f} {np.max(turns):8.2f} "
                  f"{np.nanmean([p.tilt_end_deg for p in have]):8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
