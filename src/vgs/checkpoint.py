"""Pickle-free checkpoints: tensors plus JSON metadata in one file, replaced atomically.

A checkpoint file (``checkpoint.pt`` of a training run) is a ZIP archive holding exactly

* ``meta.json``: the format tag :data:`FORMAT`, the counters and everything else that is not a
  tensor (episode, threshold, NumPy generator state, monitor values ...), as JSON;
* ``tensors.pt``: a ``torch.save`` of a nested dict/list of tensors and plain numbers, read back
  with ``torch.load(..., weights_only=True)``, whose unpickler builds tensors and built-in
  containers only and refuses every other object.

Format ``vgs-checkpoint/3`` keeps the replay buffer as scene seeds,
from which the heightmaps are re-rendered (:mod:`vgs.grasping.replay`); ``vgs-checkpoint/2``
kept the heightmaps themselves (351 kB a transition). Both are read (:data:`READS`); the
training loop turns a /2 replay into scene seeds when it resumes one.

So reading a checkpoint never runs code from the file: a file that is not such an archive (an
older vgs checkpoint, a crafted pickle, a truncated copy) is refused with a
:class:`vgs.errors.CheckpointError` before anything in it is unpickled. The ZIP's CRCs catch a
damaged file; :func:`read_meta` checks them without importing torch (``vgs status``).

Writes go to a temporary file in the same folder, are flushed to disk and renamed over the old
checkpoint (``os.replace``): a kill leaves the old checkpoint or the new one, never half of one.

This module also holds the file access every run folder shares (:func:`read_regular`,
:func:`check_regular`, :func:`open_append`, :func:`loads_json`): vgs opens only regular files
(never through a symlink, never a device or FIFO), checks their size before reading them, and
bounds JSON nesting and integers, so a planted special file ends in one line, not a hang or an
out-of-memory kill.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import stat
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from vgs.errors import CheckpointError, CorruptFileError
from vgs.jsonsafe import dumps

FORMAT = "vgs-checkpoint/3"
READS = ("vgs-checkpoint/2", FORMAT)
META = "meta.json"
TENSORS = "tensors.pt"


# Size bounds checked before a file of a run folder is read [bytes].
MAX_CHECKPOINT_BYTES = 8 << 30  # a vgs-checkpoint/2 of 5000 stored transitions is 1.75 GB
MAX_JSON_BYTES = 16 << 20  # metadata: run.json, meta.json, summary.json ...
MAX_JOURNAL_BYTES = 1 << 30  # journals and tables (a row is about 1 kB)
MAX_JSON_DEPTH = 32  # nesting of any JSON vgs reads back
_MAX_INT_DIGITS = 64  # integers vgs writes: at most 128 bits (a PCG64 generator state)


def _open_regular(path: Path, flags: int) -> int:
    """A descriptor of ``path`` opened without following a symlink and without blocking on a
    FIFO; refused unless it is a regular file.

    Raises:
        CheckpointError: (a :class:`vgs.errors.CorruptFileError`) if ``path`` is a symlink,
            device, FIFO, socket or folder.
    """
    try:
        fd = os.open(path, flags | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise CorruptFileError(path, "is a symbolic link; vgs reads and writes only "
                                         "regular files in a run folder") from None
        if exc.errno == errno.ENXIO:  # a FIFO opened for writing with no reader
            raise CorruptFileError(path, "is not a regular file (a FIFO); vgs reads and "
                                         "writes only regular files in a run folder") from None
        raise
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "not a file")
        raise CorruptFileError(path, f"is not a regular file ({kind}); vgs reads and writes "
                                     "only regular files in a run folder")
    os.set_blocking(fd, True)
    return fd


def check_regular(path: Path, limit: int) -> int:
    """The size of ``path``, a regular file (not a symlink, device or FIFO) of at most
    ``limit`` bytes.

    Raises:
        CorruptFileError: Otherwise; FileNotFoundError if it does not exist.
    """
    fd = _open_regular(path, os.O_RDONLY)
    try:
        size = os.fstat(fd).st_size
    finally:
        os.close(fd)
    _check_size(path, size, limit)
    return size


def _check_size(path: Path, size: int, limit: int) -> None:
    if size > limit:
        raise CorruptFileError(path, f"is {size} bytes, more than the {limit} bytes vgs reads "
                                     "from such a file; it is not what vgs wrote")


def read_regular(path: Path, limit: int = MAX_JSON_BYTES) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes, read through one
    descriptor (no symlink followed, no FIFO waited on).

    Raises:
        CorruptFileError: If it is a symlink, device, FIFO or folder, or larger than ``limit``;
            FileNotFoundError if it does not exist.
    """
    fd = _open_regular(path, os.O_RDONLY)
    with os.fdopen(fd, "rb") as fh:
        _check_size(path, os.fstat(fd).st_size, limit)
        data = fh.read(limit + 1)
    _check_size(path, len(data), limit)
    return data


def open_append(path: Path) -> Any:
    """``path`` opened for appending text (UTF-8), created if missing; never through a symlink
    (a dangling one included) and only a regular file.

    Raises:
        CorruptFileError: If ``path`` is a symlink or not a regular file.
    """
    fd = _open_regular(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    return os.fdopen(fd, "a", encoding="utf-8", newline="")


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > _MAX_INT_DIGITS:
        raise ValueError(f"an integer of {len(text)} digits")
    return int(text)


def loads_json(data: bytes | str, path: Path, line: int | None = None) -> Any:
    """Strict-enough JSON of a run folder's file: UTF-8, nested at most :data:`MAX_JSON_DEPTH`
    deep, integers of at most 64 digits (bare ``NaN`` of old files is read).

    Raises:
        CorruptFileError: Naming ``path`` (and ``line``) when it is not UTF-8, not JSON, nested
            too deep or holds an oversized integer.
    """
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
    except UnicodeDecodeError:
        raise CorruptFileError(path, "is not UTF-8 text; restore it or use a new folder",
                               line=line) from None
    if _depth(text) > MAX_JSON_DEPTH:
        raise CorruptFileError(path, f"nests JSON deeper than {MAX_JSON_DEPTH} levels; it is not "
                                     "what vgs wrote", line=line)
    try:
        return json.loads(text, parse_int=_bounded_int)
    except json.JSONDecodeError as exc:
        what = "is empty" if not text.strip() else f"is not JSON ({exc.msg})"
        raise CorruptFileError(path, f"{what}; restore it or use a new folder",
                               line=line) from None
    except (ValueError, RecursionError) as exc:
        raise CorruptFileError(path, f"is not JSON vgs wrote ({exc})", line=line) from None


def _depth(text: str) -> int:
    """The deepest bracket nesting of JSON text (brackets inside strings are not counted)."""
    if "[" not in text and "{" not in text:
        return 0
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            if depth > deepest:
                deepest = depth
                if deepest > MAX_JSON_DEPTH:
                    return deepest
        elif ch in "]}":
            depth -= 1
    return deepest


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and ``os.replace``.

    The temporary file (``.NAME.tmp``) is created afresh (a leftover one, or a symlink planted
    under its name, is removed first), so nothing is written outside the folder."""
    tmp = path.with_name(f".{path.name}.tmp")
    with contextlib.suppress(FileNotFoundError):
        os.unlink(tmp)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    with os.fdopen(fd, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` through a temporary file and ``os.replace``."""
    atomic_write_bytes(path, text.encode("utf-8"))


def save(path: Path, tensors: dict[str, Any], meta: dict[str, Any]) -> None:
    """Write a checkpoint atomically.

    Args:
        path: The checkpoint file.
        tensors: Nested dicts/lists of tensors, numbers, strings, booleans and None.
        meta: JSON-serialisable metadata (``format`` is added).
    """
    import torch

    buffer = io.BytesIO()
    torch.save(tensors, buffer)
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w", compression=zipfile.ZIP_STORED) as zf:
        zf.writestr(META, dumps({"format": FORMAT, **meta}, indent=1))
        zf.writestr(TENSORS, buffer.getvalue())
    atomic_write_bytes(path, archive.getvalue())


@contextlib.contextmanager
def _open(path: Path) -> Iterator[zipfile.ZipFile]:
    """The checkpoint archive, opened as a regular file of bounded size (no symlink followed,
    no FIFO waited on), with exactly vgs's two entries."""
    if not path.exists() and not path.is_symlink():
        raise CheckpointError(path, "does not exist")
    try:
        fd = _open_regular(path, os.O_RDONLY)
    except CorruptFileError as exc:
        raise CheckpointError(path, exc.message) from None
    with os.fdopen(fd, "rb") as fh:
        try:
            _check_size(path, os.fstat(fd).st_size, MAX_CHECKPOINT_BYTES)
        except CorruptFileError as exc:
            raise CheckpointError(path, exc.message) from None
        try:
            zf = zipfile.ZipFile(fh)
        except zipfile.BadZipFile:
            raise CheckpointError(path, "is not a vgs checkpoint (written by an older vgs, "
                                        "damaged, or not by vgs); refused without reading it: "
                                        "train again into a new folder") from None
        with zf:
            if set(zf.namelist()) != {META, TENSORS}:
                raise CheckpointError(path, "is not a vgs checkpoint (an older vgs's pickled "
                                            "checkpoint or a foreign file); refused without "
                                            "unpickling it: train again into a new folder")
            if any(i.compress_type != zipfile.ZIP_STORED or i.file_size > MAX_CHECKPOINT_BYTES
                   for i in zf.infolist()):  # vgs stores its entries uncompressed
                raise CheckpointError(path, "is not a vgs checkpoint (compressed or oversized "
                                            "entries); train again into a new folder")
            yield zf


# The metadata of a checkpoint (beside ``format``): key -> the types it must hold.
META_SCHEMA: dict[str, tuple[type, ...]] = {
    "episode": (int,), "threshold": (int, float, type(None)),
    "exploration_times": (list, type(None)), "rng_state": (dict, type(None)),
    "monitor": (dict,), "agent": (dict,), "replay": (dict,),
    "table_sha256": (str, type(None)), "run": (dict, type(None)),
}


LOAD_REQUIRED = ("episode", "monitor", "agent", "replay")


def read_meta(path: Path, verify: bool = True) -> dict[str, Any]:
    """The metadata of a checkpoint, without torch and without unpickling anything.

    Args:
        path: The checkpoint file.
        verify: Also check the CRC of every entry (reads the whole file).

    Raises:
        CheckpointError: If the file is missing, not a vgs checkpoint, or damaged.
    """
    with _open(path) as zf:
        if verify:
            try:
                bad = zf.testzip()
            except (zipfile.BadZipFile, OSError, EOFError) as exc:
                raise CheckpointError(path, f"is damaged ({exc})") from None
            if bad is not None:
                raise CheckpointError(path, f"is damaged (entry {bad} fails its CRC)")
        info = zf.getinfo(META)
        if info.file_size > MAX_JSON_BYTES:
            raise CheckpointError(path, f"has metadata of {info.file_size} bytes, more than "
                                        f"the {MAX_JSON_BYTES} vgs reads")
        try:
            meta = loads_json(zf.read(META), path)
        except CorruptFileError as exc:
            raise CheckpointError(path, f"has unreadable metadata ({exc.message})") from None
        except zipfile.BadZipFile as exc:
            raise CheckpointError(path, f"has unreadable metadata ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") not in READS:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise CheckpointError(path, f"has format {found!r}, this vgs reads "
                                    f"{' and '.join(map(repr, READS))}")
    check_meta(path, meta, ("episode",))
    return meta


def check_meta(path: Path, meta: dict[str, Any], required: tuple[str, ...]) -> None:
    """A checkpoint's metadata against :data:`META_SCHEMA`: the ``required`` keys present, each
    key it holds of its types, the episode counter >= 0.

    Raises:
        CheckpointError: Naming the key.
    """
    for key, kinds in META_SCHEMA.items():
        if key not in meta:
            if key in required:
                raise CheckpointError(path, f"has metadata without {key!r}; train again into a "
                                            "new folder")
            continue
        if not isinstance(meta[key], kinds) or isinstance(meta[key], bool):
            raise CheckpointError(path, f"has metadata whose {key!r} is a "
                                        f"{type(meta[key]).__name__}; train again into a new "
                                        "folder")
    if meta["episode"] < 0:
        raise CheckpointError(path, f"has metadata whose 'episode' is {meta['episode']}")


def load(path: Path, map_location: str = "cpu") -> tuple[dict[str, Any], dict[str, Any]]:
    """``(tensors, meta)`` of a checkpoint written by :func:`save`.

    The tensors are read with ``torch.load(..., weights_only=True)``.

    Raises:
        CheckpointError: If the file is missing, not a vgs checkpoint, or damaged.
    """
    import pickle

    import torch

    meta = read_meta(path, verify=True)
    check_meta(path, meta, LOAD_REQUIRED)
    with _open(path) as zf:
        data = zf.read(TENSORS)
    try:
        tensors = torch.load(io.BytesIO(data), map_location=map_location, weights_only=True)
    except (pickle.UnpicklingError, RuntimeError, EOFError, ValueError, TypeError) as exc:
        first = " ".join(str(exc).split())[:160]
        raise CheckpointError(path, f"holds tensors that cannot be read safely ({first})") \
            from None
    if not isinstance(tensors, dict):
        raise CheckpointError(path, "holds no dictionary of tensors")
    return tensors, meta
