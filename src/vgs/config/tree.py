"""Walking a configuration tree: dotted overrides, plain dicts and back, comparing a saved one."""

from __future__ import annotations

import dataclasses
import json
import sys
from dataclasses import fields, is_dataclass, replace
from typing import Any

from vgs.errors import ConfigError, VGSError

NO_SUCH_FIELD = "no such configuration field"


def override(cfg: Any, path: str, value: Any) -> Any:
    """Return a copy of a nested frozen dataclass with the dotted field ``path`` set to ``value``.

    Example: ``override(cfg, "cell.peg.mass", 0.6)``. Validation runs again on every level.

    Raises:
        ConfigError: If the path names no field (the error names the whole path) or the value is
            invalid (the error names the field as its validator does, e.g. ``hole.clearance``).
    """
    head, _, rest = path.partition(".")
    if not is_dataclass(cfg) or head not in {f.name for f in fields(cfg)}:
        raise ConfigError(path, NO_SUCH_FIELD)
    if rest:
        try:
            inner = override(getattr(cfg, head), rest, value)
        except ConfigError as exc:
            if exc.field == rest and exc.message == NO_SUCH_FIELD:  # name it from the top
                raise ConfigError(path, exc.message) from None
            raise
        return replace(cfg, **{head: inner})
    return replace(cfg, **{head: value})


def to_dict(cfg: Any) -> dict[str, Any]:
    """Plain-dict view (for JSON) of a configuration."""
    return dataclasses.asdict(cfg)


def from_dict(cls: type, data: dict[str, Any]) -> Any:
    """Rebuild a nested frozen dataclass from :func:`to_dict` output.

    A field the data lacks takes its default, except where the class names in its
    ``RECORDED_BEFORE`` mapping the value that configurations recorded before the field existed
    were made with (a changed default must not change what an old run folder describes).
    """
    kwargs = {}
    legacy: dict[str, Any] = getattr(cls, "RECORDED_BEFORE", {})
    for f in fields(cls):
        if f.name not in data:
            if f.name in legacy:
                kwargs[f.name] = legacy[f.name]
            continue
        value = data[f.name]
        namespace = vars(sys.modules[cls.__module__])  # where cls's annotations are names
        ftype = f.type if isinstance(f.type, type) else namespace.get(str(f.type), None)
        if isinstance(ftype, type) and is_dataclass(ftype) and isinstance(value, dict):
            value = from_dict(ftype, value)
        elif isinstance(value, list):
            value = tuple(tuple(v) if isinstance(v, list) else v for v in value)
        kwargs[f.name] = value
    return cls(**kwargs)


def without_retired(cls: type, data: dict[str, Any]) -> dict[str, Any]:
    """``data`` (:func:`to_dict` output of a ``cls``) without the fields vgs has removed.

    A class names them in its ``RETIRED`` tuple: settings that could change no result and were
    taken out (CHANGELOG.md). A configuration recorded while they existed reads as one without
    them, so its run folder stays resumable.
    """
    retired: tuple[str, ...] = getattr(cls, "RETIRED", ())
    out = {}
    for key, value in data.items():
        if key in retired:
            continue
        ftype = next((f.type for f in fields(cls) if f.name == key), None)
        namespace = vars(sys.modules[cls.__module__])
        ftype = ftype if isinstance(ftype, type) else namespace.get(str(ftype), None)
        if isinstance(ftype, type) and is_dataclass(ftype) and isinstance(value, dict):
            value = without_retired(ftype, value)
        out[key] = value
    return out


def same_config(saved: Any, cfg: Any) -> bool:
    """Whether ``saved`` (:func:`to_dict` output, e.g. read from a run's JSON) describes ``cfg``.

    Fields added to vgs since ``saved`` was written take their defaults, so folders made by an
    earlier version stay resumable as long as nothing they recorded differs. Unknown fields or
    values the dataclasses reject make it a different configuration.
    """
    if not isinstance(saved, dict):
        return False
    try:
        saved_cfg = from_dict(type(cfg), saved)
    except (TypeError, ValueError, VGSError):
        return False
    return json.dumps(to_dict(saved_cfg)) == json.dumps(to_dict(cfg))
