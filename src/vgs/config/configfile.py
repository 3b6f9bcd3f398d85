"""Configuration files: a whole :class:`~vgs.config.experiment.ExperimentConfig` read from a file,
as ``--config FILE`` takes it.

Three shapes are read, JSON or TOML (by the suffix ``.toml``; JSON otherwise):

- the list ``[{"key": "cell.peg.mass", "value": 0.5, "doc": ...}, ...]`` that ``vgs config
  --json`` prints (``doc`` is ignored);
- a nested table ``{"cell": {"peg": {"mass": 0.5}}, ...}``, the shape of :func:`to_dict` and
  of a TOML file (``[cell.peg]`` / ``mass = 0.5``);
- a run folder's metadata (``run.json``, ``meta.json``, ``sweep.json``, ``reproduce.json``):
  a table whose ``config`` entry is the recorded configuration.

A key the first two leave out takes the ``paper`` profile's value (the dataclass defaults); a
recorded configuration reads as a resume reads it (:func:`from_dict`: a field added since takes
the value the run was made with, a retired one is dropped). TOML has no null, so a TOML file
cannot set a key to ``None``; JSON can.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import is_dataclass
from pathlib import Path
from typing import Any

from vgs.config.experiment import ExperimentConfig
from vgs.config.tree import NO_SUCH_FIELD, from_dict, override, without_retired
from vgs.errors import ConfigError


def read_config_file(path: str | Path) -> ExperimentConfig:
    """The configuration the file ``path`` holds (module docstring: the shapes it reads).

    Raises:
        ConfigError: ``config`` if the file cannot be read or has none of the shapes; the dotted
            key if a key names no field or its value is invalid.
    """
    path = Path(path)
    data = _load(path)
    if isinstance(data, dict) and isinstance(data.get("config"), dict):  # a run's metadata
        recorded = without_retired(ExperimentConfig, data["config"])
        try:
            return from_dict(ExperimentConfig, _tuples(recorded))
        except (TypeError, ValueError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError("config", f"{path}: records no usable configuration "
                                        f"({exc})") from None
    if isinstance(data, list):
        pairs = []
        for item in data:
            if not (isinstance(item, dict) and isinstance(item.get("key"), str)
                    and "value" in item):
                raise ConfigError("config", f"{path}: expected a list of {{key, value}} "
                                            f"entries (vgs config --json), got {item!r:.60}")
            pairs.append((item["key"], item["value"]))
    elif isinstance(data, dict):
        pairs = list(_leaves(ExperimentConfig(), data, ""))
    else:
        raise ConfigError("config", f"{path}: holds no configuration (a table of sections or "
                                    "the key list of vgs config --json)")
    cfg = ExperimentConfig()
    for key, value in pairs:
        if is_dataclass(_current(cfg, key)):
            raise ConfigError(key, f"is a group of keys, not one key (in {path})")
        try:
            cfg = override(cfg, key, _tuples(value))
        except ConfigError as exc:
            if exc.message == NO_SUCH_FIELD:
                raise ConfigError(exc.field, f"{NO_SUCH_FIELD} (in {path}; vgs config lists "
                                             "them)") from None
            raise
        except (TypeError, ValueError) as exc:
            raise ConfigError(key, f"invalid value {value!r} in {path} ({exc})") from None
    return cfg


def _load(path: Path) -> Any:
    """The parsed file: TOML by the suffix ``.toml``, JSON otherwise."""
    try:
        if path.suffix.lower() == ".toml":
            with path.open("rb") as stream:
                return tomllib.load(stream)
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError("config", f"{path}: no such file") from None
    except IsADirectoryError:
        raise ConfigError("config", f"{path}: is a folder; name a file") from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        kind = "TOML" if path.suffix.lower() == ".toml" else "JSON"
        raise ConfigError("config", f"{path}: not valid {kind} ({exc})") from None


def _current(cfg: Any, key: str) -> Any:
    """The value at the dotted ``key`` of ``cfg``, or None if there is none."""
    for name in key.split("."):
        cfg = getattr(cfg, name, None)
    return cfg


def _leaves(cfg: Any, table: dict[str, Any], prefix: str) -> list[tuple[str, Any]]:
    """``(dotted key, value)`` of each leaf of the nested ``table``, descending into a table only
    where ``cfg`` has a section of that name (so a key whose value is a table but whose field is
    not a section is reported by :func:`override`)."""
    out = []
    for name, value in table.items():
        section = getattr(cfg, name, None) if is_dataclass(cfg) else None
        if isinstance(value, dict) and is_dataclass(section):
            out += _leaves(section, value, f"{prefix}{name}.")
        else:
            out.append((f"{prefix}{name}", value))
    return out


def _tuples(value: Any) -> Any:
    """``value`` with every list a tuple, nested too (the configuration's sequences are tuples);
    the values of tables are converted likewise."""
    if isinstance(value, list):
        return tuple(_tuples(item) for item in value)
    if isinstance(value, dict):
        return {key: _tuples(item) for key, item in value.items()}
    return value
