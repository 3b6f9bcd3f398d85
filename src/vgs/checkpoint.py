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
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path
from typing import Any

from vgs.errors import CheckpointError
from vgs.jsonsafe import dumps

FORMAT = "vgs-checkpoint/3"
READS = ("vgs-checkpoint/2", FORMAT)
META = "meta.json"
TENSORS = "tensors.pt"


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and ``os.replace``."""
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("wb") as fh:
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


def _open(path: Path) -> zipfile.ZipFile:
    if not path.exists():
        raise CheckpointError(path, "does not exist")
    try:
        zf = zipfile.ZipFile(path)
    except zipfile.BadZipFile:
        raise CheckpointError(path, "is not a vgs checkpoint (written by an older vgs, damaged, "
                                    "or not by vgs); refused without reading it: train again "
                                    "into a new folder") from None
    names = set(zf.namelist())
    if names != {META, TENSORS}:
        zf.close()
        raise CheckpointError(path, "is not a vgs checkpoint (an older vgs's pickled checkpoint "
                                    "or a foreign file); refused without unpickling it: train "
                                    "again into a new folder")
    return zf


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
        try:
            meta = json.loads(zf.read(META).decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError, zipfile.BadZipFile) as exc:
            raise CheckpointError(path, f"has unreadable metadata ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") not in READS:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise CheckpointError(path, f"has format {found!r}, this vgs reads "
                                    f"{' and '.join(map(repr, READS))}")
    return meta


def load(path: Path, map_location: str = "cpu") -> tuple[dict[str, Any], dict[str, Any]]:
    """``(tensors, meta)`` of a checkpoint written by :func:`save`.

    The tensors are read with ``torch.load(..., weights_only=True)``.

    Raises:
        CheckpointError: If the file is missing, not a vgs checkpoint, or damaged.
    """
    import pickle

    import torch

    meta = read_meta(path, verify=True)
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
