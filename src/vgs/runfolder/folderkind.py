"""What kind of run folder a folder is, told by its metadata file, so that no command writes into
a folder of another kind (an evaluation's ``episodes.csv`` over a training run's table).

=============  ==================  ==============================================
kind           metadata            written by
=============  ==================  ==============================================
training run   ``run.json``        ``vgs train`` (also a policy folder)
evaluation     ``meta.json``       ``vgs evaluate``
sweep          ``sweep.json``      ``vgs sweep`` (folders written before it: their
                                   ``journal.jsonl`` of sweep rows or ``sweep.csv``)
reproduction   ``reproduce.json``  ``vgs reproduce``
=============  ==================  ==============================================

A folder without metadata is told by the files it holds (a training table's header, a
checkpoint, a journal's first row), so a folder whose metadata was lost is still refused by a
command of another kind. What each folder was made from (configuration, policy digest, sweep
plan) is checked by the command that resumes it.
"""

from __future__ import annotations

from pathlib import Path

from vgs.errors import RunMismatchError

KINDS = ("training run", "evaluation", "sweep", "reproduction")
MARKERS = {"run.json": "training run", "meta.json": "evaluation", "sweep.json": "sweep",
           "reproduce.json": "reproduction"}
_TRAIN_HEADER = b"episode,mode,seed,"


def kinds_in(folder: Path) -> dict[str, str]:
    """The kinds of run folder whose files ``folder`` holds, each with the file that tells it
    (empty for a missing or empty folder)."""
    found: dict[str, str] = {}
    if not folder.is_dir():
        return found
    for name, kind in MARKERS.items():
        if (folder / name).exists() or (folder / name).is_symlink():
            found.setdefault(kind, name)
    if "training run" not in found:
        for name in ("checkpoint.pt", "policy.pt"):
            if (folder / name).is_file():
                found.setdefault("training run", name)
        if _starts_with(folder / "episodes.csv", _TRAIN_HEADER):
            found.setdefault("training run", "episodes.csv")
    if "sweep" not in found and (folder / "sweep.csv").is_file():
        found["sweep"] = "sweep.csv"
    journal = folder / "journal.jsonl"
    if not ({"evaluation", "sweep"} & set(found)) and journal.is_file():
        found["sweep" if _starts_with(journal, b'{"index": ', b'"offset_mm"') else
              "evaluation"] = "journal.jsonl"
    return found


def _starts_with(path: Path, prefix: bytes, contains: bytes | None = None) -> bool:
    """Whether the regular file ``path`` starts with ``prefix`` (and its first line holds
    ``contains``); reads at most 4 kB."""
    if not path.is_file() or path.is_symlink():
        return False
    try:
        with path.open("rb") as fh:
            head = fh.read(4096)
    except OSError:
        return False
    first = head.split(b"\n", 1)[0]
    return head.startswith(prefix) and (contains is None or contains in first)


def claim(folder: Path, kind: str) -> None:
    """Refuse ``folder`` if it holds a run folder of another kind than ``kind``; reads only.

    Raises:
        RunMismatchError: ``out``, naming the kind found and the file that tells it.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown kind {kind!r}")
    others = {k: name for k, name in kinds_in(folder).items() if k != kind}
    if others:
        other, name = next(iter(others.items()))
        raise RunMismatchError("out", f"{folder} holds {_a(other)} ({name}), not {_a(kind)}; a "
                                      "command writes only into an empty folder or one of its "
                                      "own kind: use another folder")


def _a(kind: str) -> str:
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"
