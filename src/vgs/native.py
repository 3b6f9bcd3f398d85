"""The per-tick kernels in C (``src/vgs/_native.c``), loaded after MuJoCo's library.

A control tick runs the arm (F/T sample, payload compensation, the wrench at the TCP, the
admittance, two damped least-squares IK steps), the pads' stick latch and, for the record, the
grasp watch. Written on Python
floats they cost about 100 us of interpreter time per tick, a third of an episode beside
``mj_step``; in C a few microseconds. The C does the same operations in the same order as the
Python floats it replaced (:mod:`vgs.vecmath`'s formulas; each function names its Python
original), compiled without fused multiply-adds or fast-math and calling libm and MuJoCo's own
routines as the Python did, so the golden records did not change and a tick gives the same bits
on every x86-64 CPU (``tests/test_kernels.py``).

The kernels keep no state of their own: they read and write numpy arrays owned by their Python
objects (:class:`vgs.control.arm.ArmController`, :class:`vgs.sim.stiction.PadStiction`,
:class:`vgs.assembly.episode.GraspWatch`),
whose data pointers they take once, and MuJoCo's ``mjModel``/``mjData`` by address.

No vgs imports: every package may use it.
"""

from __future__ import annotations

import mujoco  # noqa: F401  (loads libmujoco, which vgs._native links to by its soname)

try:
    from vgs import _native
except ImportError as exc:  # pragma: no cover - a broken build
    raise ImportError(
        "vgs._native, the per-tick kernels in C, is not built: reinstall vgs "
        "(pip install -e '.[dev]' compiles src/vgs/_native.c; it needs a C compiler)"
    ) from exc

arm_new = _native.arm_new
arm_update = _native.arm_update
arm_commanded = _native.arm_commanded
arm_gravity_wrench = _native.arm_gravity_wrench
admittance_step = _native.admittance_step
latch_new = _native.latch_new
latch_update = _native.latch_update
latch_weld_wrench = _native.latch_weld_wrench
watch_new = _native.watch_new
heightmap_fill = _native.heightmap_fill
watch_sample = _native.watch_sample

__all__ = ["admittance_step", "arm_commanded", "arm_gravity_wrench", "arm_new", "arm_update",
           "heightmap_fill", "latch_new", "latch_update", "latch_weld_wrench", "watch_new",
           "watch_sample"]
