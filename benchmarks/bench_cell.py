"""Speed of the simulated cell: physics steps per second, real-time factor, controller overhead.

Run: ``.venv/bin/python benchmarks/bench_cell.py [--episodes 5] [--steps 5000] [--set KEY=VALUE]``
(``--set`` as in the ``vgs`` commands, e.g. ``--set cell.sim.noslip_iterations=1``).

Prints, for one process pinned to one CPU core:

* physics steps per second of the full cell (``mujoco.mj_step`` only) with the robot holding
  still at home, and during whole assemblies;
* the real-time factor of whole episodes (look, grasp, assemble, release): simulated seconds
  divided by wall seconds, beside that of ``mj_step`` alone during the same episodes (simulated
  seconds divided by the seconds spent inside ``mj_step``) and their ratio, which is the share
  of an episode's time spent in the physics and does not depend on how fast the host is;
* the share of wall time spent outside ``mj_step`` (the Python controller, the camera, the
  bookkeeping), measured by wrapping ``mujoco.mj_step`` with a timer, and the Python per control
  tick: the time outside ``mj_step`` and the camera divided by the control ticks (one
  ``mj_step`` call of ``sim.control_decimation`` steps each).

numpy's BLAS runs on one thread (``OPENBLAS_NUM_THREADS=1`` unless set otherwise). Every figure
above is measured twice: with the wall clock and with this process's CPU time. On an idle core
the two agree; when other processes share the core, the CPU-time figures are what an idle core
would give, and the wall-clock ones show the slowdown.

The same episodes then run a second time with a wall-clock timer around each part of the
control tick, to split the Python per tick (us per tick; the timers' own cost, calibrated on an
empty function, is removed; the parts' sum is this second run's Python per tick):

* ``arm``: the arm's tick, F/T sample and wrench at the TCP, admittance and inverse kinematics
  (``ArmController.update``; in C, ``vgs.native.arm_update``, with the noise block's draw);
* ``latch``: the pads' stick latch after the physics steps (``PadStiction.update``; in C);
* ``watch``: the record's grasp watch (the robot's observers, ``GraspWatch``);
* ``state machine``: the grasp and assembly primitives between ticks (``grasp`` and
  ``AssemblyModule.run`` less their ticks);
* ``rest``: the rest of the tick (gripper ramp, the loop, the divergence check) and of the
  episode (reset, policy, record).

``--timers`` then runs the same episodes again with MuJoCo's internal timers on
(``mujoco.set_mjcb_time``) and prints where the time inside ``mj_step`` goes, per stage, in
microseconds per step (the timer callback itself costs time, so these runs are not used for the
figures above).

Last, one centre-grasp episode runs in a subprocess under each of two ``OPENBLAS_CORETYPE``
values (``--kernels``, default ``Haswell,host``) and the script prints whether its record and
final simulator state are identical: a check of this machine's instrument (docs/architecture.md,
"One instrument on every CPU").

Targets on one core of the project machine (issue 51): Python per control tick <= 30 us, whole
episodes / ``mj_step`` alone >= 0.85. Figures only, no assertions.
"""

from __future__ import annotations

import os

# One process on one core: without this, numpy's OpenBLAS starts a helper thread on the other
# core at import; the camera's large matrix product wakes it, it spins for a while after, and
# its time counts in this process's CPU time (about 5 % of an episode's on a 2-core host).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable, Iterator  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from typing import Any  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import vgs.assembly.episode  # noqa: E402
from vgs.assembly.episode import EpisodeRunner, GraspWatch, center_policy  # noqa: E402
from vgs.assembly.strategy import AssemblyModule  # noqa: E402
from vgs.config import ExperimentConfig, override, profile  # noqa: E402
from vgs.control.arm import ArmController  # noqa: E402
from vgs.control.robot import Robot  # noqa: E402
from vgs.sim.cell import HOME_Q, Cell  # noqa: E402
from vgs.sim.stiction import PadStiction  # noqa: E402


@dataclass
class Clock:
    """Wall and CPU seconds."""

    wall: float = 0.0
    cpu: float = 0.0

    def add(self, wall: float, cpu: float) -> None:
        self.wall += wall
        self.cpu += cpu


@contextmanager
def measure(clock: Clock) -> Iterator[None]:
    """Add the wall and CPU time of the block to ``clock``."""
    w0, c0 = time.perf_counter(), time.process_time()
    try:
        yield
    finally:
        clock.add(time.perf_counter() - w0, time.process_time() - c0)


@dataclass
class StepTimer:
    """Time and number of physics steps spent in ``mujoco.mj_step``, and in the camera."""

    physics: Clock = field(default_factory=Clock)
    camera: Clock = field(default_factory=Clock)
    steps: int = 0
    calls: int = 0


@contextmanager
def timed_mj_step(timer: StepTimer) -> Iterator[StepTimer]:
    """Replace ``mujoco.mj_step`` by a timing wrapper for the duration of the block."""
    original = mujoco.mj_step
    wall, cpu = time.perf_counter, time.process_time

    def wrapper(m: mujoco.MjModel, d: mujoco.MjData, nstep: int = 1) -> None:
        # The clocks read directly (a context manager would add its own cost per tick to the
        # time outside mj_step).
        w0, c0 = wall(), cpu()
        original(m, d, nstep)
        timer.physics.add(wall() - w0, cpu() - c0)
        timer.steps += nstep
        timer.calls += 1

    mujoco.mj_step = wrapper
    try:
        yield timer
    finally:
        mujoco.mj_step = original


def pin_to_one_core() -> str:
    """Restrict this process to one CPU core where the OS allows it."""
    if hasattr(os, "sched_setaffinity"):
        core = min(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {core})
        return f"pinned to core {core}"
    return "not pinned (no sched_setaffinity)"


def steps_holding_still(steps: int, cfg: ExperimentConfig) -> Clock:
    """Time of ``steps`` physics steps with the arm servoed at home and the peg on the table."""
    cell = Cell(cfg.cell, cfg.controller.joint_kp, cfg.controller.joint_kv)
    cell.reset(np.random.default_rng(0))
    m, d = cell.model, cell.data
    d.ctrl[cell.ids.arm_act] = HOME_Q
    mujoco.mj_step(m, d, 200)  # settle
    clock = Clock()
    with measure(clock):
        for _ in range(steps):
            mujoco.mj_step(m, d)
    return clock


def _timed(fn: Callable[..., Any], clock: Clock) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with measure(clock):
            return fn(*args, **kwargs)

    return wrapper


@dataclass(frozen=True)
class AssemblyTiming:
    """Where the time of whole episodes went."""

    episodes: int
    successes: int
    sim_s: float
    total: Clock
    timer: StepTimer


def assemblies(episodes: int, cfg: ExperimentConfig, seed: int) -> AssemblyTiming:
    """Run whole episodes (centre grasp) in this process and time them."""
    runner = EpisodeRunner(cfg)
    _, camera = runner.cell(cfg.cell.peg)  # compile outside the timing
    timer = StepTimer()
    camera.capture = _timed(camera.capture, timer.camera)
    total = Clock()
    sim = 0.0
    successes = 0
    with timed_mj_step(timer):
        for k in range(episodes):
            with measure(total):
                record, robot, _ = runner.run(seed + k, center_policy())
            sim += robot.time
            successes += int(record.success)
    return AssemblyTiming(episodes, successes, sim, total, timer)


@dataclass
class Part:
    """Wall seconds and calls of one timed function; ``inner_calls``: timed calls nested in it
    that its seconds leave out (a scope's ticks)."""

    seconds: float = 0.0
    calls: int = 0
    inner_calls: int = 0


def _timed_part(fn: Callable[..., Any], part: Part) -> Callable[..., Any]:
    """``fn`` with its wall time added to ``part`` (inclusive of what it calls)."""
    perf = time.perf_counter

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = perf()
        try:
            return fn(*args, **kwargs)
        finally:
            part.seconds += perf() - t0
            part.calls += 1

    return wrapper


def _timed_scope(fn: Callable[..., Any], part: Part, inner: Part) -> Callable[..., Any]:
    """``fn`` with its wall time, less that of the ``inner`` calls it makes, added to ``part``."""
    perf = time.perf_counter

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0, s0, n0 = perf(), inner.seconds, inner.calls
        try:
            return fn(*args, **kwargs)
        finally:
            part.seconds += perf() - t0 - (inner.seconds - s0)
            part.calls += 1
            part.inner_calls += inner.calls - n0

    return wrapper


@contextmanager
def patched(replacements: list[tuple[Any, str, Callable[..., Any]]]) -> Iterator[None]:
    """Set ``owner.name = value`` for each replacement during the block."""
    originals = [(owner, name, getattr(owner, name)) for owner, name, _ in replacements]
    for owner, name, value in replacements:
        setattr(owner, name, value)
    try:
        yield
    finally:
        for owner, name, value in originals:
            setattr(owner, name, value)


def timer_cost(calls: int = 100_000, repeats: int = 5) -> tuple[float, float]:
    """Seconds one :func:`_timed_part` call adds per call: inside its own measurement, and in
    all to its caller (the least of ``repeats`` runs on an empty function)."""

    def noop() -> None:
        return None

    inside = added = float("inf")
    for _ in range(repeats):
        part = Part()
        timed = _timed_part(noop, part)
        t0 = time.perf_counter()
        for _ in range(calls):
            noop()
        bare = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(calls):
            timed()
        wrapped = time.perf_counter() - t0
        inside = min(inside, (part.seconds - bare) / calls)
        added = min(added, (wrapped - bare) / calls)
    return max(inside, 0.0), added


TICK_PARTS = ("arm", "latch", "watch", "state machine", "rest")


def tick_split(episodes: int, cfg: ExperimentConfig, seed: int) -> tuple[dict[str, float], int]:
    """Python per control tick by part [s] over whole episodes (the same as
    :func:`assemblies`), from wall-clock timers around the parts; and the ticks."""
    runner = EpisodeRunner(cfg)
    _, camera = runner.cell(cfg.cell.peg)
    names = ("update", "latch", "watch", "tick", "mj_step", "camera", "grasp", "run")
    p = {name: Part() for name in names}
    replacements = [
        (ArmController, "update", _timed_part(ArmController.update, p["update"])),
        (PadStiction, "update", _timed_part(PadStiction.update, p["latch"])),
        (GraspWatch, "__call__", _timed_part(GraspWatch.__call__, p["watch"])),
        (Robot, "tick", _timed_part(Robot.tick, p["tick"])),
        (mujoco, "mj_step", _timed_part(mujoco.mj_step, p["mj_step"])),
        (camera, "capture", _timed_part(camera.capture, p["camera"])),
        (vgs.assembly.episode, "grasp",
         _timed_scope(vgs.assembly.episode.grasp, p["grasp"], p["tick"])),
        (AssemblyModule, "run", _timed_scope(AssemblyModule.run, p["run"], p["tick"])),
    ]
    inside, added = timer_cost()
    total = 0.0
    with patched(replacements):
        for k in range(episodes):
            t0 = time.perf_counter()
            runner.run(seed + k, center_policy())
            total += time.perf_counter() - t0

    def own(name: str) -> float:
        """Seconds of ``name`` less its own timer's share."""
        return p[name].seconds - p[name].calls * inside

    split = {
        "arm": own("update"),
        "latch": own("latch"),
        "watch": own("watch"),
        "state machine": sum(own(n) - p[n].inner_calls * (added - inside)
                             for n in ("grasp", "run")),
    }
    python = (total - own("mj_step") - own("camera")
              - sum(part.calls for part in p.values()) * added)
    split["rest"] = python - sum(split.values())
    ticks = p["mj_step"].calls
    return {name: seconds / ticks for name, seconds in split.items()}, ticks


def report_split(split: dict[str, float], ticks: int) -> None:
    print(f"Python per control tick by part (second run, wall clock, {ticks:,} ticks):")
    for name in TICK_PARTS:
        print(f"  {name:38s}{1e6 * split[name]:8.1f} us")
    print(f"  {'sum':38s}{1e6 * sum(split.values()):8.1f} us")


# Stages of mj_step timed by MuJoCo (engine_forward.c); the collision and position stages nest
# inside "position", which nests inside "forward".
STAGES = (
    ("step", "mjTIMER_STEP"),
    ("  kinematics", "mjTIMER_POS_KINEMATICS"),
    ("  inertia", "mjTIMER_POS_INERTIA"),
    ("  collision, broad phase", "mjTIMER_COL_BROAD"),
    ("  collision, narrow phase", "mjTIMER_COL_NARROW"),
    ("  constraint set-up", "mjTIMER_POS_MAKE"),
    ("  constraint projection", "mjTIMER_POS_PROJECT"),
    ("  velocity", "mjTIMER_VELOCITY"),
    ("  actuation", "mjTIMER_ACTUATION"),
    ("  constraint solver", "mjTIMER_CONSTRAINT"),
    ("  integration", "mjTIMER_ADVANCE"),
)


def stage_times(episodes: int, cfg: ExperimentConfig, seed: int) -> tuple[dict[str, float], int]:
    """Seconds per stage of ``mj_step`` (MuJoCo's timers) over whole episodes, and the steps."""
    runner = EpisodeRunner(cfg)
    cell, _ = runner.cell(cfg.cell.peg)
    totals = {name: 0.0 for _, name in STAGES}
    steps = 0
    mujoco.set_mjcb_time(time.perf_counter)
    try:
        for k in range(episodes):
            runner.run(seed + k, center_policy())  # reset clears the timers
            for _, name in STAGES:
                totals[name] += cell.data.timer[int(getattr(mujoco.mjtTimer, name))].duration
            steps += cell.data.timer[int(mujoco.mjtTimer.mjTIMER_STEP)].number
    finally:
        mujoco.set_mjcb_time(None)
    return totals, steps


def report_stages(totals: dict[str, float], steps: int) -> None:
    step = totals["mjTIMER_STEP"]
    print(f"inside mj_step (MuJoCo timers, {steps:,} steps; the timer callback adds overhead):")
    for label, name in STAGES:
        print(f"  {label:34s}{1e6 * totals[name] / steps:8.1f} us/step"
              f"{100 * totals[name] / step:7.1f} %")


def report(still: Clock, steps: int, r: AssemblyTiming, timestep: float) -> None:
    """Print the figures, CPU-time based and wall-clock based."""
    t = r.timer
    print(f"{'':40s}{'CPU time':>12s}{'wall clock':>12s}")

    def line(label: str, cpu: float, wall: float, fmt: str, note: str = "") -> None:
        print(f"{label:40s}{cpu:>12{fmt}}{wall:>12{fmt}}  {note}")

    line("mj_step, holding still [steps/s]", steps / still.cpu, steps / still.wall, ",.0f",
         f"({steps / still.cpu * timestep:.0f} x real time)")
    line("mj_step, during assemblies [steps/s]", t.steps / t.physics.cpu,
         t.steps / t.physics.wall, ",.0f",
         f"({t.steps / t.physics.cpu * timestep:.0f} x real time)")
    line("real-time factor of whole episodes", r.sim_s / r.total.cpu, r.sim_s / r.total.wall,
         ".1f")
    line("real-time factor of their mj_step alone", r.sim_s / t.physics.cpu,
         r.sim_s / t.physics.wall, ".1f")
    line("  ratio whole episodes / mj_step alone", t.physics.cpu / r.total.cpu,
         t.physics.wall / r.total.wall, ".2f", "(host-independent; target >= 0.85)")
    line("time outside mj_step [%]", 100 * (1 - t.physics.cpu / r.total.cpu),
         100 * (1 - t.physics.wall / r.total.wall), ".1f", "(target <= 15 %)")
    line("  of which camera ray casting [%]", 100 * t.camera.cpu / r.total.cpu,
         100 * t.camera.wall / r.total.wall, ".1f")
    rest_cpu = r.total.cpu - t.physics.cpu - t.camera.cpu
    rest_wall = r.total.wall - t.physics.wall - t.camera.wall
    line("  Python per control tick [us]", 1e6 * rest_cpu / t.calls, 1e6 * rest_wall / t.calls,
         ".0f", f"over {t.calls:,} ticks (target <= 30 us)")
    print(f"episodes: {r.episodes} ({r.successes} assembled), {r.sim_s:.1f} s simulated, "
          f"{r.total.cpu:.1f} s CPU, {r.total.wall:.1f} s wall")
    if r.total.wall > 1.1 * r.total.cpu:
        print("note: wall clock > 1.1 x CPU time: other processes shared the core")


def episode_record(profile_name: str, seed: int, overrides: list[str]) -> str:
    """One centre-grasp episode of ``seed`` as its record row and a digest of the final
    simulator state (JSON text), in this process."""
    import hashlib

    cfg = profile(profile_name)
    for item in overrides:
        key, _, value = item.partition("=")
        cfg = override(cfg, key, json.loads(value))
    record, robot, _ = EpisodeRunner(cfg).run(seed, center_policy())
    d = robot.cell.data
    row = {k: repr(v) for k, v in record.to_row().items()}
    row["state_sha256"] = hashlib.sha256(np.concatenate([d.qpos, d.qvel]).tobytes()).hexdigest()
    return json.dumps(row, sort_keys=True)


def compare_kernels(kernels: list[str], profile_name: str, seed: int, overrides: list[str]
                    ) -> None:
    """Run one episode under each ``OPENBLAS_CORETYPE`` value (``host``: the environment as it
    is) in a subprocess and print whether the records are identical."""
    import subprocess
    import sys

    rows = {}
    for kernel in kernels:
        env = dict(os.environ)
        if kernel != "host":
            env["OPENBLAS_CORETYPE"] = kernel
        cmd = [sys.executable, __file__, "--record-only", "--profile", profile_name,
               "--seed", str(seed), *(f"--set={s}" for s in overrides)]
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            print(f"kernel {kernel}: the episode failed: {proc.stderr.strip()[-300:]}")
            return
        rows[kernel] = json.loads(proc.stdout)
    names = [k if k != "host" else f"host ({os.environ.get('OPENBLAS_CORETYPE', 'unset')})"
             for k in kernels]
    first = rows[kernels[0]]
    differ = sorted({key for k in kernels for key in first if rows[k].get(key) != first[key]})
    verdict = "identical" if not differ else f"DIFFERENT in {', '.join(differ)}"
    print(f"one episode (seed {seed}, centre grasp) under OPENBLAS_CORETYPE "
          f"{' / '.join(names)}: record and final state {verdict} "
          f"(assembly {first['assembly_time_s']} s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5, help="whole episodes to time")
    parser.add_argument("--steps", type=int, default=5000, help="steps of the still benchmark")
    parser.add_argument("--profile", default="paper")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--all-cores", action="store_true", help="do not pin to one core")
    parser.add_argument("--timers", action="store_true",
                        help="also print the stages of mj_step (MuJoCo's timers)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="configuration override (JSON value), e.g. "
                             "cell.sim.noslip_iterations=1; repeatable")
    parser.add_argument("--kernels", default="Haswell,host",
                        help="compare one episode's record under these OPENBLAS_CORETYPE values "
                             "(comma-separated; 'host': as the environment sets it; '': skip)")
    parser.add_argument("--record-only", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.record_only:
        print(episode_record(args.profile, args.seed, args.set))
        return
    pinned = "not pinned" if args.all_cores else pin_to_one_core()
    cfg = profile(args.profile)
    for item in args.set:
        key, _, value = item.partition("=")
        cfg = override(cfg, key, json.loads(value))
    print(f"vgs cell benchmark: mujoco {mujoco.__version__}, {platform.machine()}, {pinned}, "
          f"time step {1000 * cfg.cell.sim.timestep:g} ms, control every "
          f"{cfg.cell.sim.control_decimation} steps, no-slip iterations "
          f"{cfg.cell.sim.noslip_iterations}" + "".join(f", {s}" for s in args.set))
    still = steps_holding_still(args.steps, cfg)
    timing = assemblies(args.episodes, cfg, args.seed)
    report(still, args.steps, timing, cfg.cell.sim.timestep)
    report_split(*tick_split(args.episodes, cfg, args.seed))
    if args.timers:
        report_stages(*stage_times(args.episodes, cfg, args.seed))
    kernels = [k for k in args.kernels.split(",") if k]
    if len(kernels) >= 2:
        compare_kernels(kernels, args.profile, args.seed, args.set)


if __name__ == "__main__":
    main()
