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
_MAX_SEED = 2**63 - 1


def check_seed(field: str, value: Any) -> int:
    """``value`` as a seed: a non-negative integer (not a bool).

    Raises:
        ConfigError: ``field`` otherwise.
    """
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= _MAX_SEED:
        raise ConfigError(field, f"a seed must be a non-negative integer, got {value!r}")
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
        raise ConfigError(field, f"expected {_describe(tp)}, got {value!r}")
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, tuple):
            raise ConfigError(field, f"expected a tuple, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(f"{field}[{i}]", v, args[0]) for i, v in enumerate(value))
        if args and len(args) != len(value):
            raise ConfigError(field, f"expected {len(args)} items, got {value!r}")
        return tuple(_coerce(f"{field}[{i}]", v, a)
                     for i, (v, a) in enumerate(zip(value, args, strict=False)))
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(field, f"expected a number, got {value!r}")
        if isinstance(value, int) and not math.isfinite(float(value)):
            raise ConfigError(field, f"number out of range: {value!r}")
        if not math.isfinite(value):  # run folders record the configuration as strict JSON
            raise ConfigError(field, f"must be a finite number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(field, f"expected an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(field, f"expected True or False, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(field, f"expected a string, got {value!r}")
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


def check_config(cfg: Any) -> Any:
    """``cfg`` with its types checked and ints of float fields made floats; seeds checked.

    Raises:
        ConfigError: Naming the first field with a wrong type or a bad seed.
    """
    cfg = _walk(cfg, "")
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
