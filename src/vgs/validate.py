"""Type and range checks of a whole configuration, run before a command writes anything.

The dataclasses of :mod:`vgs.config` check their ranges in ``__post_init__``; they do not check
types, so ``--set cell.peg.mass=True`` or ``--set seed=abc`` would be taken and fail later (or
never). :func:`check_config` walks the configuration against its type annotations:

* ``float`` takes an int or a float, never a bool (ints are stored as floats, so ``12`` and
  ``12.0`` are the same configuration);
* ``int`` takes an int, never a bool;
* ``bool`` takes a bool only; ``str`` a string; ``X | None`` also None;
* ``tuple[T, ...]`` and ``tuple[T, U]`` take tuples whose items pass;

and every seed (``seed``, ``reproduce.train_seeds``, ``reproduce.eval_seed``) must be a
non-negative integer (NumPy's seed sequences take no negative numbers).
"""

from __future__ import annotations

import math
import types
import typing
from dataclasses import fields, is_dataclass, replace
from typing import Any

from vgs.errors import ConfigError

SEED_FIELDS = ("seed", "reproduce.eval_seed", "reproduce.train_seeds")
MAX_SEED = 2**63 - 1


def check_seed(field: str, value: Any) -> int:
    """``value`` as a seed: a non-negative integer (not a bool).

    Raises:
        ConfigError: ``field`` otherwise.
    """
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_SEED:
        raise ConfigError(field, f"a seed must be a non-negative integer, got {_shown(value)}")
    return value


def _describe(tp: Any) -> str:
    return getattr(tp, "__name__", None) or str(tp).replace("typing.", "")


def _coerce(field: str, value: Any, tp: Any) -> Any:
    """``value`` checked against the annotation ``tp`` (ints become floats for ``float``)."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        options = typing.get_args(tp)
        if value is None and type(None) in options:
            return None
        errors = []
        for option in options:
            if option is type(None):
                continue
            try:
                return _coerce(field, value, option)
            except ConfigError as exc:
                errors.append(exc)
        raise ConfigError(field, f"expected {_describe(tp)}, got {_shown(value)}")
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, tuple):
            raise ConfigError(field, f"expected a tuple, got {_shown(value)}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(f"{field}[{i}]", v, args[0]) for i, v in enumerate(value))
        if args and len(args) != len(value):
            raise ConfigError(field, f"expected {len(args)} items, got {_shown(value)}")
        return tuple(_coerce(f"{field}[{i}]", v, a)
                     for i, (v, a) in enumerate(zip(value, args, strict=False)))
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(field, f"expected a number, got {_shown(value)}")
        if isinstance(value, int) and abs(value) > 1e300:  # float() of it would overflow
            raise ConfigError(field, f"number out of range: a number of {len(str(value))} "
                                     "digits")
        if not math.isfinite(value):  # run folders record the configuration as strict JSON
            raise ConfigError(field, f"must be a finite number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(field, f"expected an integer, got {_shown(value)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(field, f"expected True or False, got {_shown(value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(field, f"expected a string, got {_shown(value)}")
        return value
    return value  # an annotation this checker does not know: the dataclass checks it


def _walk(cfg: Any, prefix: str) -> Any:
    try:
        hints = typing.get_type_hints(type(cfg))
    except (NameError, TypeError):  # an annotation this module cannot resolve: check each
        hints = {}
        namespace = vars(__import__(type(cfg).__module__, fromlist=["_"]))
        for f in fields(cfg):
            try:
                hints[f.name] = eval(f.type, namespace) if isinstance(f.type, str) else f.type  # noqa: S307
            except Exception:  # noqa: BLE001 - leave that field to its dataclass
                continue
    changes = {}
    for f in fields(cfg):
        value = getattr(cfg, f.name)
        path = f"{prefix}{f.name}"
        if is_dataclass(value):
            new = _walk(value, f"{path}.")
        else:
            new = _coerce(path, value, hints.get(f.name, Any))
        if repr(new) != repr(value):  # (repr tells 12 from 12.0, also inside tuples)
            changes[f.name] = new
    return replace(cfg, **changes) if changes else cfg


# What the machine can hold and the cell can be: every numeric setting that sizes memory, time
# or the physics has a bound, checked with the types (dotted path -> (lowest, highest)).
MAX_EPISODES = 1_000_000
MAX_TIME_S = 3600.0  # the longest phase time-out (vgs.config.control.MAX_PHASE_TIMEOUT_S)
BOUNDS: dict[str, tuple[float, float]] = {
    "train.episodes": (1, MAX_EPISODES), "eval.episodes": (1, MAX_EPISODES),
    "train.checkpoint_every": (1, MAX_EPISODES), "train.parallel_episodes": (1, 256),
    "agent.random_episodes": (0, MAX_EPISODES), "agent.replay_capacity": (1, 1_000_000),
    "agent.replay_batch": (1, 1024), "agent.delta_q_window": (1, MAX_EPISODES),
    "network.num_rotations": (1, 64),
    "cell.camera.size": (16, 1024), "cell.camera.pixel_size": (1e-4, 0.02),
    "cell.camera.height": (0.1, 5.0),
    "cell.peg.mass": (1e-3, 50.0), "cell.peg.length": (0.05, 0.5),
    "cell.peg.diameter": (1e-3, 0.11), "cell.hole.depth": (1e-3, 0.5),
    "cell.hole.clearance": (0.0, 0.05), "cell.hole.outer_radius": (1e-3, 0.3),
    "cell.hole.segments": (8, 512), "cell.hole.peg_diameter": (1e-3, 0.11),
    "cell.sim.timestep": (1e-5, 0.01), "cell.sim.control_decimation": (1, 1000),
    "cell.sim.noslip_iterations": (0, 1000), "cell.gripper.force": (3.0, 40.0),
    "reproduce.sweep_offsets": (0, 1000), "reproduce.sweep_trials": (0, 100_000),
    # Counts of the assembly's loops.
    "assembly.max_retries": (0, 100), "assembly.max_align_adjustments": (1, 1000),
    "assembly.max_insert_stalls": (0, 1000), "assembly.plane_window": (1, 1000),
    # Times [s]: each at most the longest phase time-out (and, below, its phase's own).
    "assembly.settle_time": (0.0, MAX_TIME_S), "assembly.slide_settle_time": (0.0, MAX_TIME_S),
    "assembly.still_time": (0.0, MAX_TIME_S), "assembly.hop_press_time": (0.0, MAX_TIME_S),
    "assembly.hop_settle_time": (0.0, MAX_TIME_S), "assembly.wiggle_period": (0.01, MAX_TIME_S),
    "cell.sim.contact_timeconst": (2e-5, 1.0),
    # Speeds [m/s, rad/s]: at least a millimetre a second, so that every move ends.
    "assembly.approach_speed": (1e-3, 1.0), "assembly.slide_speed": (1e-3, 1.0),
    "assembly.insert_speed": (1e-3, 1.0), "assembly.hop_lift_speed": (1e-3, 1.0),
    "assembly.hop_speed": (1e-3, 1.0), "assembly.hop_descent_speed": (1e-3, 1.0),
    "controller.max_speed": (1e-3, 2.0), "controller.max_angular_speed": (1e-2, 10.0),
    "cell.gripper.closing_speed": (1e-3, 1.0),
    # Rates.
    "cell.ft.cutoff_hz": (0.0, 1000.0), "agent.learning_rate": (1e-12, 10.0),
    "agent.weight_decay": (0.0, 1.0), "reward.threshold_percentile": (0.0, 100.0),
}

# The waits of each assembly phase that run without a look at its time-out (vgs.assembly: the
# settles after a move, a touch-down's press, the slide's rest window, a wiggle): together they
# must fit within the phase's time-out, so that no phase outlives it.
PHASE_WAITS: dict[str, tuple[str, ...]] = {
    "transport": ("settle_time", "settle_time"),  # before the peg's estimate; after the move
    "approach": ("settle_time", "settle_time"),  # after a retry's turn; after the tilt
    "search": ("hop_settle_time", "hop_press_time"),
    "slide": ("slide_settle_time", "still_time"),
    "align": ("wiggle_period",),
    "insert": ("wiggle_period",),
}


def check_phase_waits(assembly: Any) -> None:
    """Each phase's waits (:data:`PHASE_WAITS`) summed, ``sum(w) <= timeout(phase)``.

    Raises:
        ConfigError: Naming the longest wait of the first phase they overrun, its sum and the
            time-out.
    """
    for phase, names in PHASE_WAITS.items():
        total = sum(float(getattr(assembly, name)) for name in names)
        limit = assembly.timeout(phase)
        if total > limit:
            longest = max(names, key=lambda name: float(getattr(assembly, name)))
            parts = " + ".join(f"{getattr(assembly, name):g}" for name in names)
            raise ConfigError(f"assembly.{longest}", f"the {phase} phase waits {parts} = "
                                                     f"{total:g} s between its time-out checks; "
                                                     f"at most its time-out {limit:g} s "
                                                     f"(assembly.timeouts)")


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def bound_text(low: float, high: float) -> str:
    """``[low, high]`` as a refusal names it: whole numbers written out (``1000000``)."""
    def one(x: float) -> str:
        return str(int(x)) if float(x).is_integer() and abs(x) < 1e16 else f"{x:g}"
    return f"[{one(low)}, {one(high)}]"


def check_bounds(cfg: Any) -> None:
    """Every field of :data:`BOUNDS` within its bound.

    Raises:
        ConfigError: Naming the field and the bound.
    """
    for path, (low, high) in BOUNDS.items():
        value: Any = cfg
        for name in path.split("."):
            value = getattr(value, name, None)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if not low <= value <= high:
            raise ConfigError(path, f"must lie in {bound_text(low, high)}, got {_shown(value)}")


def check_config(cfg: Any) -> Any:
    """``cfg`` with its types checked and ints of float fields made floats; seeds, the
    bounds of :data:`BOUNDS` and the phases' waits (:func:`check_phase_waits`) checked.

    Raises:
        ConfigError: Naming the first field with a wrong type, a bad seed or a value out of
            its bound.
    """
    cfg = _walk(cfg, "")
    check_bounds(cfg)
    check_phase_waits(cfg.assembly)
    check_seed("seed", cfg.seed)
    check_seed("reproduce.eval_seed", cfg.reproduce.eval_seed)
    for i, seed in enumerate(cfg.reproduce.train_seeds):
        check_seed(f"reproduce.train_seeds[{i}]", seed)
    return cfg


def config_differences(saved: dict[str, Any], request: dict[str, Any],
                       prefix: str = "") -> list[str]:
    """Dotted paths of the fields whose values differ between two :func:`vgs.config.to_dict`
    views (recorded JSON against a request), in field order."""
    out = []
    for key in list(request) + [k for k in saved if k not in request]:
        a, b = saved.get(key, "<absent>"), request.get(key, "<absent>")
        if isinstance(a, dict) and isinstance(b, dict):
            out += config_differences(a, b, f"{prefix}{key}.")
        elif _normal(a) != _normal(b):
            out.append(f"{prefix}{key}")
    return out


def _normal(value: Any) -> Any:
    if isinstance(value, (list, tuple)):
        return [_normal(v) for v in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return float(value)
    return value
