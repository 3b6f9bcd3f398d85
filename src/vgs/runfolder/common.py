"""What every run folder (training run, evaluation, reproduction) shares: a lock, atomic JSON
metadata, checked reading of JSON files, the comparison of a request with the recorded
configuration, and the host a row was computed on.

Torch-free: ``vgs status`` uses it.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import functools
import os
import platform
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from vgs.checkpoint import (
    MAX_JOURNAL_BYTES,
    MAX_JSON_BYTES,
    atomic_write_text,
    check_regular,
    loads_json,
    read_regular,
)
from vgs.errors import CorruptFileError, FolderBusyError, RunMismatchError
from vgs.jsonsafe import dumps
from vgs.revision import short_revision as short_revision  # re-exported for analysis/
from vgs.revision import source_revision
from vgs.runfolder.schema import check_json, check_table

LOCK_NAME = ".lock"


@contextlib.contextmanager
def locked(folder: Path) -> Iterator[None]:
    """Hold ``folder/.lock`` (``fcntl.flock``, exclusive) while the block runs.

    The kernel drops the lock when the process ends, however it ends, so a killed run never
    leaves a stale lock behind. A folder this call created is removed again when the block
    fails before anything but the lock was written in it.

    Raises:
        FolderBusyError: If another process holds it.
    """
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    ok = False
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise FolderBusyError(f"{folder} is in use by another vgs process (lock "
                                      f"{folder / LOCK_NAME}); wait for it or use another "
                                      "folder") from None
            raise
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield
        ok = True
    finally:
        if not ok and created and [p.name for p in folder.iterdir()] == [LOCK_NAME]:
            # A command refused before it wrote anything leaves no folder behind.
            (folder / LOCK_NAME).unlink(missing_ok=True)
            with contextlib.suppress(OSError):
                folder.rmdir()
        os.close(fd)  # releases the lock


def read_json(path: Path, kind: type = dict) -> Any:
    """The JSON document in ``path``, which must be a ``kind``: a regular file (no symlink,
    device or FIFO) of at most 16 MiB, nested at most 32 deep
    (:func:`vgs.checkpoint.read_regular`, :func:`vgs.checkpoint.loads_json`); a metadata file
    of :data:`vgs.runfolder.schema.JSON_SCHEMAS` of its shape and types.

    Raises:
        CorruptFileError: If it is empty, not UTF-8, not JSON, not a ``kind``, a special file or
            too large.
    """
    data = loads_json(read_regular(path, MAX_JSON_BYTES), path)
    if not isinstance(data, kind):
        raise CorruptFileError(path, f"holds a {type(data).__name__}, not a "
                                     f"{kind.__name__}")
    check_json(path, data)  # run.json, meta.json, reproduce.json: their schema
    return data


def write_json(path: Path, data: Any) -> None:
    """Write ``data`` as strict JSON (NaN and infinities as ``null``,
    :func:`vgs.jsonsafe.dumps`) to ``path`` atomically (temporary file, then ``os.replace``)."""
    atomic_write_text(path, dumps(data, indent=2))


def check_request(saved: dict[str, Any], cfg: Any, where: Path,
                  extendable: tuple[str, ...] = ()) -> list[str]:
    """Compare the configuration recorded in a run folder with the one requested.

    Fields added to vgs since the folder was written take their defaults; fields it removed
    (a class's ``RETIRED``, :func:`vgs.config.without_retired`) are ignored. A field in
    ``extendable`` (dotted paths such as ``train.episodes``) may grow: those that did are
    returned; any other difference, or one of them shrinking, is refused.

    Raises:
        RunMismatchError: Naming the first field that differs.
        CorruptFileError: If the recorded configuration cannot be read by this vgs.
    """
    from vgs.config import from_dict, to_dict, without_retired
    from vgs.errors import VGSError
    from vgs.validate import config_differences

    saved = without_retired(type(cfg), saved)  # fields vgs removed (changing no result)
    try:
        saved_cfg = from_dict(type(cfg), saved)
    except (TypeError, ValueError, VGSError) as exc:
        raise CorruptFileError(where, f"records a configuration this vgs cannot read ({exc})") \
            from None
    old, new = to_dict(saved_cfg), to_dict(cfg)
    unknown = _unknown(saved, old)
    if unknown:
        raise RunMismatchError(unknown, f"{where} records a field this vgs does not know "
                                        "(written by another version); use a new folder")
    grown = []
    for path in config_differences(old, new):
        if path in extendable:
            a, b = _get(old, path), _get(new, path)
            if isinstance(a, int) and isinstance(b, int) and b > a:
                grown.append(path)
                continue
            raise RunMismatchError(path, f"{where} was made with another configuration ({a!r}, "
                                         f"not {b!r}); this field can only grow (to extend the "
                                         "run); use a new folder otherwise")
        raise RunMismatchError(path, f"{where} was made with another configuration "
                                     f"({_get(old, path)!r}, not {_get(new, path)!r}); repeat "
                                     "the run's settings to resume it, or use a new folder")
    return grown


def run_identity(meta: dict[str, Any]) -> dict[str, Any]:
    """What names a training run (its ``run.json``, checked by
    :mod:`vgs.runfolder.schema`): ``run_id`` (made when the run started; runs begun before
    it have none), ``mode`` and ``seed``. Each checkpoint records it (``run``)."""
    return {"run_id": meta.get("run_id"), "mode": meta["mode"], "seed": meta["config"]["seed"]}


def check_belongs(recorded: Any, meta: dict[str, Any], path: Path, run_json: Path) -> None:
    """A checkpoint's ``run`` record against the identity of the run whose ``run.json``
    (``meta``) lies beside it: the same ``mode``, ``seed`` and ``run_id``. A checkpoint written
    before checkpoints named their run (no record) and a run without ``run_id`` check what they
    have.

    Raises:
        CheckpointError: Naming the field that differs.
    """
    from vgs.errors import CheckpointError

    if recorded is None:
        return
    if not isinstance(recorded, dict):
        raise CheckpointError(path, "records its run in a form this vgs does not know")
    mine = run_identity(meta)
    for key in ("mode", "seed", "run_id"):
        if mine[key] is None or key not in recorded:
            continue
        if recorded[key] != mine[key]:
            raise CheckpointError(path, f"{key}: belongs to another training run "
                                        f"({str(recorded[key])[:40]!r}; {run_json.name} records "
                                        f"{str(mine[key])[:40]!r}); restore the run's own "
                                        "checkpoint, or train into a new folder")


def check_table_digest(table: Path, ckpt: Path, saved: dict[str, Any]) -> None:
    """The first rows of a training run's ``table`` against what its checkpoint ``ckpt``
    recorded (metadata ``saved``): the header and the rows of its episodes must hash to its
    ``table_sha256`` (checkpoints written before the hash: nothing to check).

    Raises:
        CorruptFileError: If they do not (another run's table, or a changed one).
    """
    import hashlib

    digest = saved.get("table_sha256")
    if digest is None:
        return
    data = read_regular(table, MAX_JOURNAL_BYTES) if table.exists() else b""
    head = b"".join(data.splitlines(keepends=True)[:int(saved["episode"]) + 1])
    if hashlib.sha256(head).hexdigest() != digest:
        raise CorruptFileError(table, f"is not the table {ckpt.name} saw at episode "
                                      f"{saved['episode']} (its SHA-256 differs): another "
                                      "run's, or changed; restore it")


TABLE_FILES = ("episodes.parquet", "episodes.csv")


def table_digests(folder: Path) -> dict[str, str]:
    """``{file name: SHA-256}`` of an evaluation's tables in ``folder`` (written into its
    ``summary.json`` as ``tables_sha256``, so that a reader can tell the tables the evaluation
    wrote from changed ones)."""
    import hashlib

    return {name: hashlib.sha256(read_regular(folder / name, MAX_JOURNAL_BYTES)).hexdigest()
            for name in TABLE_FILES if (folder / name).exists()}


def check_table_written(table: Path) -> None:
    """An evaluation table against the SHA-256 its ``summary.json`` recorded
    (``tables_sha256``; summaries written before it record none: nothing to check).

    Raises:
        CorruptFileError: If the table is not the one the evaluation wrote.
    """
    import hashlib

    summary = table.parent / "summary.json"
    if not summary.exists():
        return
    recorded = read_json(summary).get("tables_sha256")
    if not isinstance(recorded, dict) or table.name not in recorded:
        return
    if hashlib.sha256(read_regular(table, MAX_JOURNAL_BYTES)).hexdigest() != recorded[table.name]:
        raise CorruptFileError(table, "is not the table its evaluation wrote (its SHA-256 "
                                      "differs from summary.json's): changed since; run the "
                                      "evaluation (or vgs reproduce) again to rebuild it from "
                                      "its journals")


def _unknown(saved: dict[str, Any], known: dict[str, Any], prefix: str = "") -> str | None:
    """The first dotted path in ``saved`` that ``known`` lacks, or None."""
    for key, value in saved.items():
        if key not in known:
            return f"{prefix}{key}"
        if isinstance(value, dict) and isinstance(known[key], dict):
            found = _unknown(value, known[key], f"{prefix}{key}.")
            if found:
                return found
    return None


def _get(d: dict[str, Any], path: str) -> Any:
    for name in path.split("."):
        d = d.get(name, "<absent>") if isinstance(d, dict) else "<absent>"
    return d


@functools.cache
def host() -> dict[str, str]:
    """``{"host_cpu": CPU model, "mujoco_version": ...}`` of this machine (cached).

    The CPU model comes from ``/proc/cpuinfo`` (``model name``), else ``platform.processor()``.
    MuJoCo's floating point differs between CPUs, so the same scene can end differently on two
    hosts; rows carry these fields so that mixed runs show.
    """
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text(errors="replace").splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cpu = cpu or platform.processor() or platform.machine() or "unknown"
    try:
        import mujoco

        version = str(mujoco.__version__)
    except ImportError:  # pragma: no cover - mujoco is a dependency
        version = "unknown"
    return {"host_cpu": " ".join(cpu.split()), "mujoco_version": version}


def hosts_of(rows: Any) -> list[str]:
    """Distinct ``"CPU, MuJoCo version"`` of rows (dicts) that record them, in first-seen order;
    rows written before hosts were recorded count as ``"unrecorded"`` when others record one."""
    seen: dict[str, None] = {}
    for row in rows:
        cpu, version = row.get("host_cpu"), row.get("mujoco_version")
        if _missing(cpu):
            seen.setdefault("unrecorded", None)
        else:
            seen.setdefault(f"{cpu}, MuJoCo {version}", None)
    names = list(seen)
    return [] if names == ["unrecorded"] else names


def engine_note(rows: Any) -> str:
    """One sentence when rows (dicts with ``mujoco_version``) were made with another MuJoCo than
    the installed one, else ``""``: the same scene seeds give other physics on another engine
    (pyproject.toml pins the version the published results were made with)."""
    installed = host()["mujoco_version"]
    other = sorted({str(v) for row in rows
                    if not _missing(v := row.get("mujoco_version")) and str(v) != installed})
    if not other:
        return ""
    return (f"made with MuJoCo {', '.join(other)}, installed {installed}: the same seeds can "
            "end differently on another physics engine")


def _missing(value: Any) -> bool:
    return value is None or (isinstance(value, float) and value != value) or value == ""


def read_table(path: Path, kind: str | None = None) -> Any:
    """A results table (``.parquet`` or ``.csv``) as a pandas DataFrame, in the column
    vocabulary of :mod:`vgs.columns`: tables written before it (``docs/results``) have their
    legacy columns renamed and converted, and booleans written as 0/1 made booleans
    (:func:`vgs.columns.normalize`).

    With ``kind`` (``train`` or ``eval``) the table is checked against its schema
    (:func:`vgs.runfolder.schema.check_table`).

    Raises:
        CorruptFileError: If the file cannot be parsed (truncated, not a table, not UTF-8), or
            is not of its ``kind``.
    """
    import pandas as pd

    from vgs.columns import normalize

    check_regular(path, MAX_JOURNAL_BYTES)  # no symlink, device or FIFO; bounded
    try:
        df = normalize(pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path))
    except OSError:
        raise
    except Exception as exc:  # noqa: BLE001 - pandas and pyarrow raise many kinds
        first = " ".join(str(exc).split())[:160]
        raise CorruptFileError(path, f"is not a readable table ({type(exc).__name__}: "
                                     f"{first})") from None
    if kind is not None:
        check_table(df, path, kind)
    return df


@functools.cache
def provenance() -> dict[str, str]:
    """Where a result came from, recorded (never compared) in ``run.json``, an evaluation's
    ``meta.json``, ``reproduce.json``, the parquet tables' schema metadata and the report:
    ``vgs_version``, ``source_revision`` (:func:`vgs.revision.source_revision`: the git commit
    of the checkout vgs runs from or of the tree its wheel was built from), ``mujoco_version``
    and ``torch_version`` (read from the installed distributions: torch is
    not imported).
    """
    from importlib import metadata

    def version(name: str) -> str:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "unknown"

    return {"vgs_version": version("vgs"), "source_revision": source_revision(),
            "mujoco_version": version("mujoco"), "torch_version": version("torch")}


def duration_text(seconds: float) -> str:
    """A duration in the unit that fits it: ``7.5 s``, ``42 s``, ``12.3 min``, ``2.41 h``
    (never ``0.0 h`` for seconds)."""
    if seconds < 10:
        return f"{seconds:.1f} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.2f} h"
