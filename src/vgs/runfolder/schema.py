"""One schema per file kind of a run folder, checked by every reader before the data is used.

The metadata files (``run.json``, an evaluation's ``meta.json``, ``reproduce.json``) are checked
by :func:`vgs.runfolder.common.read_json`, which every reader uses, against
:data:`JSON_SCHEMAS` (by file name); the tables (a training run's ``episodes.csv``, an
evaluation's ``episodes.parquet``/``.csv`` and the merged tables of a reproduction) by
:func:`check_table` (:func:`vgs.runfolder.common.read_table` with its ``kind``), against the
columns of :mod:`vgs.columns` and :data:`TABLE_REQUIRED`; a checkpoint's metadata by
:func:`check_checkpoint_meta`. A file of the wrong shape or types is refused in one line
naming the file and the field (:class:`vgs.errors.CorruptFileError`), never read as if whole.

Torch-free.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vgs.columns import COLUMNS
from vgs.errors import CorruptFileError


@dataclass(frozen=True)
class Field:
    """One key of a JSON document.

    Attributes:
        kinds: The JSON kinds it may hold: ``str``, ``int`` (not a bool), ``number``, ``bool``,
            ``dict``, ``list`` and ``null``.
        required: Whether the document must hold it.
        items: The kind of each item of a list, or ``""`` for any.
    """

    kinds: tuple[str, ...]
    required: bool = False
    items: str = ""


def _f(*kinds: str, required: bool = False, items: str = "") -> Field:
    return Field(kinds, required, items)


# The configuration a file records: at least these keys (every vgs has written them), so that
# an empty or foreign ``config`` is not read as the defaults (the paper profile).
CONFIG_SCHEMA: dict[str, Field] = {
    "name": _f("str", required=True), "seed": _f("int", required=True),
    "cell": _f("dict", required=True), "network": _f("dict", required=True),
    "agent": _f("dict", required=True), "train": _f("dict", required=True),
    "eval": _f("dict", required=True),
}

_PROVENANCE = _f("dict")
JSON_SCHEMAS: dict[str, dict[str, Field]] = {
    "run.json": {
        "mode": _f("str", required=True), "config": _f("dict", required=True),
        "schedule_episodes": _f("int"), "torch_threads": _f("int"),
        "git_revision": _f("str", "null"), "python": _f("str"), "torch": _f("str"),
        "hosts": _f("list", items="dict"), "provenance": _PROVENANCE,
        "resumed_with": _f("list", items="dict"),
        "run_id": _f("str"),
    },
    "meta.json": {
        "policy": _f("str", required=True), "policy_source": _f("str"),
        "policy_trained_episodes": _f("int", "null"), "policy_digest": _f("str", "null"),
        "condition": _f("str", required=True), "episodes": _f("int", required=True),
        "seed": _f("int", required=True), "config": _f("dict", required=True),
        "provenance": _PROVENANCE,
    },
    "reproduce.json": {
        "profile": _f("str", required=True), "config": _f("dict", required=True),
        "machine": _f("str", "dict", "null"), "git_revision": _f("str", "null"),
        "provenance": _PROVENANCE, "command": _f("str", "null"),
        "stage_wall_s": _f("dict"), "finished": _f("str", "null"),
    },
}
MODES = ("vgs", "baseline")


def kind_of(value: Any) -> str:
    """The JSON kind of a parsed value (``int`` for integers, ``number`` for floats)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "number"
    return {str: "str", dict: "dict", list: "list"}.get(type(value), type(value).__name__)


def check_fields(data: dict[str, Any], schema: dict[str, Field], path: Path | str,
                 prefix: str = "") -> None:
    """Each key of ``schema`` that ``data`` holds of one of its kinds (an ``int`` counts as a
    ``number``), each required one present; keys the schema does not name are left alone.

    Raises:
        CorruptFileError: Naming the first key that is missing or of another kind.
    """
    for key, spec in schema.items():
        if key not in data:
            if spec.required:
                raise CorruptFileError(path, f"{prefix}{key}: missing; the file is not "
                                             "whole (restore it, or use a new folder)")
            continue
        kind = kind_of(data[key])
        if kind not in spec.kinds and not (kind == "int" and "number" in spec.kinds):
            raise CorruptFileError(path, f"{prefix}{key}: expected "
                                         f"{' or '.join(spec.kinds)}, got {kind}")
        if spec.items and kind == "list":
            for i, item in enumerate(data[key]):
                if kind_of(item) != spec.items:
                    raise CorruptFileError(path, f"{prefix}{key}[{i}]: expected {spec.items}, "
                                                 f"got {kind_of(item)}")


def check_json(path: Path, data: Any) -> None:
    """``data``, read from ``path``, against the schema of its file name (:data:`JSON_SCHEMAS`;
    files of other names are not checked here).

    Raises:
        CorruptFileError: Naming the file and the first field of the wrong shape.
    """
    schema = JSON_SCHEMAS.get(Path(path).name)
    if schema is None:
        return
    if not isinstance(data, dict):
        raise CorruptFileError(path, f"holds a {kind_of(data)}, not an object")
    check_fields(data, schema, path)
    check_fields(data["config"], CONFIG_SCHEMA, path, "config.")
    if Path(path).name == "run.json" and data["mode"] not in MODES:
        raise CorruptFileError(path, f"mode: expected vgs or baseline, got {data['mode']!r}")
    if "schedule_episodes" in data and data["schedule_episodes"] < 1:
        raise CorruptFileError(path, "schedule_episodes: must be >= 1")
    if Path(path).name == "meta.json" and data["episodes"] < 1:
        raise CorruptFileError(path, "episodes: must be >= 1")
    walls = data.get("stage_wall_s", {})
    for stage, seconds in walls.items():
        if kind_of(seconds) not in ("int", "number"):
            raise CorruptFileError(path, f"stage_wall_s.{stage}: expected a number, got "
                                         f"{kind_of(seconds)}")


# The columns every table of a kind must hold (besides: each column vgs knows of its kind).
TABLE_REQUIRED: dict[str, tuple[str, ...]] = {
    "train": ("episode", "mode", "seed", "grasp_success", "assembly_success",
              "assembly_time_s", "wall_s"),
    "eval": ("index", "policy", "condition", "seed", "grasp_success", "assembly_success",
             "assembly_time_s"),
}


def check_header(names: list[Any], path: Path, kind: str) -> None:
    """The column names of a table of ``kind``: the required ones of :data:`TABLE_REQUIRED`,
    none outside :mod:`vgs.columns`.

    Raises:
        CorruptFileError: Naming the table and the column.
    """
    missing = [name for name in TABLE_REQUIRED[kind] if name not in names]
    if missing:
        raise CorruptFileError(path, f"is not a table of vgs ({kind}): it lacks the column "
                                     f"{missing[0]!r}")
    for name in names:
        if str(name) not in COLUMNS:
            raise CorruptFileError(path, f"holds the column {str(name)[:40]!r}, which no vgs "
                                         "table has (docs/columns.md)")


def check_table(df: Any, path: Path, kind: str) -> None:
    """A table (pandas DataFrame, read from ``path``) of ``kind`` (``train``: a training run's
    ``episodes.csv``; ``eval``: an evaluation's table or a merged one): the required columns
    of :data:`TABLE_REQUIRED`, no column outside :mod:`vgs.columns`, and each of its kind
    (booleans as booleans, integers as integers, numbers numeric, text as text or empty).

    Raises:
        CorruptFileError: Naming the table and the column.
    """
    import pandas as pd

    check_header(list(df.columns), path, kind)
    for name in df.columns:
        column = COLUMNS[str(name)]
        series = df[name]
        if series.isna().all():
            continue  # (an empty column reads as floats whatever it held)
        if column.kind == "bool":
            ok = pd.api.types.is_bool_dtype(series)
        elif column.kind == "int":
            ok = pd.api.types.is_integer_dtype(series) and not pd.api.types.is_bool_dtype(series)
        elif column.kind == "float":
            ok = pd.api.types.is_numeric_dtype(series) and not pd.api.types.is_bool_dtype(series)
        else:
            ok = pd.api.types.is_string_dtype(series) or pd.api.types.is_object_dtype(series)
            ok = ok and all(isinstance(v, str) for v in series.dropna())
        if not ok:
            raise CorruptFileError(path, f"column {name!r}: expected {column.kind} values, got "
                                         f"{series.dtype}")
