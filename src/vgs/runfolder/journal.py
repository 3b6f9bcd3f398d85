"""The journals of run folders (an evaluation's and a sweep's ``journal.jsonl``): one JSON row per
finished episode, appended as it ends, under one integrity rule.

Each line is strict JSON (NaN as ``null``) in the column vocabulary of :mod:`vgs.columns` and
carries ``crc32``, the CRC-32 of the row's JSON without it (:func:`encode_row`), so a row changed
after it was written is caught. A row without ``crc32`` is refused, except in the leading rows
written before the rule, which are accepted only when those lines hash (SHA-256) to a digest
vgs knows: one of the journals the project published (:data:`PUBLISHED`, the committed
``docs/results`` journals) or the digest a folder's metadata recorded when this vgs first
resumed it (a sweep folder written before ``sweep.json`` existed: :mod:`vgs.experiments.sweep`).
Rows written before the vocabulary (legacy names such as ``peg_mass``, ``success``, bare
``NaN``) are read too: the checksum is checked on the row as written, then the row is put in
the vocabulary (:func:`vgs.columns.normalize_row`).

A journal is read only as a regular file inside its folder (no symlink, device or FIFO) of at
most 1 GiB (:func:`vgs.checkpoint.read_regular`) and appended through
:func:`vgs.checkpoint.open_append` (never through a symlink). Read back with checks (torch-,
pandas- and MuJoCo-free, so ``vgs status`` stays quick): every line must be UTF-8 JSON holding a
row whose checksum matches; no index may come twice; with the plan given, each row must be the
planned episode of its index (episode seed, peg mass and length). The one exception is the last
line when a kill cut it short (no JSON): it is dropped and its episode runs again.
"""

from __future__ import annotations

import hashlib
import json
import math
import zlib
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vgs.checkpoint import MAX_JOURNAL_BYTES, loads_json, read_regular
from vgs.columns import normalize_row
from vgs.errors import CorruptFileError
from vgs.jsonsafe import dumps

# SHA-256 of the journals vgs published before every row carried a checksum (the committed
# docs/results/**/journal.jsonl): their rows are accepted without one.
PUBLISHED = frozenset({
    "fca480ff94e77da4dc8c226dd69d0d49a0c1d836a3807adb16fe3235d1d2553c",  # cell_stiction/com200
    "388ff13764f88fe2703a2ee32818364162d67281396d313ba1c7c57d976b41fd",  # cell_stiction/sweep
    "1752901138ac37852aaf2503f72baf9654f51cfb5c18c7fc62ad1a7269d204f1",  # .../sweep_mass_length
    "32ca2e6c020a1b83fb851b1110064be113ff6dd6fae59d8a95f7425d826b1ab9",  # cell_graspable
})


@dataclass
class Lines:
    """The checked rows of a journal.

    Attributes:
        rows: ``(line number, row)`` in file order, each row's checksum checked and removed.
        cut: Whether a last line cut short by a kill was dropped.
        unterminated: Whether the last row lacks its newline (a kill between the row and its
            newline): the row is kept, and a writer must end the line before appending.
        legacy: ``{"lines": n, "sha256": digest}`` of the leading rows without a checksum, or
            None when every row has one.
    """

    rows: list[tuple[int, dict[str, Any]]] = field(default_factory=list)
    cut: bool = False
    legacy: dict[str, Any] | None = None
    unterminated: bool = False


def read_lines(path: Path, legacy: Collection[str] = PUBLISHED,
               any_legacy: bool = False) -> Lines:
    """The rows of a journal under the integrity rule (module docstring).

    Args:
        path: The journal (absent: no rows).
        legacy: Digests of leading rows without checksums that are accepted.
        any_legacy: Accept any leading rows without checksums (a folder whose metadata predates
            the rule, resumed for the first time; the caller records :attr:`Lines.legacy`).

    Raises:
        CorruptFileError: Naming the file (and line) of a special or oversized file, a line
            that is not UTF-8 JSON of a row, a changed row, or a row without a checksum that
            the rule does not accept.
    """
    out = Lines()
    if not path.exists() and not path.is_symlink():
        return out
    data = read_regular(path, MAX_JOURNAL_BYTES)
    lines = data.split(b"\n")
    unchecked = 0
    for number, raw in enumerate(lines, start=1):
        last = number == len(lines)
        if not raw.strip():
            if last:
                continue
            raise CorruptFileError(path, "is an empty line, not a row", line=number)
        try:
            row = loads_json(raw, path, line=number)
        except CorruptFileError:
            if last and not raw.endswith(b"}"):  # a line cut short by a kill: run it again
                out.cut = True
                continue
            raise
        if not isinstance(row, dict):
            raise CorruptFileError(path, "is not a row (a JSON object)", line=number)
        if "crc32" in row:
            crc = row.pop("crc32")
            # Python's JSON of the parsed row is the text written: null stays null, and the bare
            # NaN of journals written before strict JSON stays NaN.
            if crc != zlib.crc32(json.dumps(row).encode()):
                raise CorruptFileError(path, "was changed after it was written (its checksum "
                                             "does not match); restore the journal or use a new "
                                             "folder", line=number)
        else:
            unchecked = number
        out.rows.append((number, row))
        out.unterminated = last
    if unchecked:
        digest = hashlib.sha256(b"".join(line + b"\n" for line in lines[:unchecked])).hexdigest()
        if not any_legacy and digest not in legacy:
            raise CorruptFileError(path, "holds a row without its crc32 checksum; only journals "
                                         "written before the checksum, whose rows vgs "
                                         "recorded, may lack it: restore the journal or use a "
                                         "new folder", line=unchecked)
        out.legacy = {"lines": unchecked, "sha256": digest}
    return out


def encode_row(row: dict[str, Any]) -> str:
    """One journal line (with its newline): the row's strict JSON (NaN as ``null``) plus its
    ``crc32``, the CRC-32 of that JSON."""
    body = dumps(row)
    return f"{body[:-1]}, \"crc32\": {zlib.crc32(body.encode())}}}\n"


ROW_KEYS = ("index", "seed", "peg_mass_kg", "peg_length_mm", "assembly_success",
            "grasp_success", "assembly_time_s", "failure_reason")


def read_journal(path: Path, plan: Sequence[Any] | None = None
                 ) -> tuple[dict[int, dict[str, Any]], bool]:
    """The rows of a ``journal.jsonl`` by episode index, checked and in the column vocabulary
    (:func:`vgs.columns.normalize_row`: legacy names renamed, ``null`` floats as NaN); and
    whether the journal must be written again before appending (a cut last line was dropped,
    or the last row lacks its newline).

    Args:
        path: The journal.
        plan: The planned episodes (:class:`vgs.rollout.episodepool.EpisodeTask`); each
            row must match the episode of its index (episode seed, peg mass and length).
            None checks the rows' form only (``vgs status``).

    Raises:
        CorruptFileError: Naming the file and line of a line that is not UTF-8, not JSON (but
            for the last line when a kill cut it short), not an episode row, a row without its
            checksum (:func:`read_lines`), a duplicate, or a row of another plan.
    """
    rows: dict[int, dict[str, Any]] = {}
    required = ROW_KEYS if plan is not None else ("index", "assembly_success")
    found = read_lines(path)
    first: dict[int, int] = {}
    for number, row in found.rows:
        row = normalize_row(row)
        if any(k not in row for k in required) \
                or isinstance(row["index"], bool) or not isinstance(row["index"], int):
            raise CorruptFileError(path, "is not an episode row of an evaluation", line=number)
        i = row["index"]
        if i in first:
            raise CorruptFileError(path, f"repeats episode {i} (first at line {first[i]}); "
                                         "restore the journal or use a new folder", line=number)
        if plan is not None:
            _check_row(path, number, row, plan)
        first[i] = number
        rows[i] = row
    return rows, found.cut or found.unterminated


def _check_row(path: Path, number: int, row: dict[str, Any], plan: Sequence[Any]) -> None:
    i = row["index"]
    if not 0 <= i < len(plan):
        raise CorruptFileError(path, f"holds episode {i}, outside the {len(plan)} planned "
                                     "episodes: another evaluation's row", line=number)
    task = plan[i]

    def same(a: Any, b: float) -> bool:
        return isinstance(a, (int, float)) and not isinstance(a, bool) and math.isclose(
            float(a), b, rel_tol=1e-9, abs_tol=1e-12)

    problems = []
    if row["seed"] != task.seed:
        problems.append(f"seed {row['seed']} (planned {task.seed})")
    if not same(row["peg_mass_kg"], task.peg.mass):
        problems.append(f"peg mass {row['peg_mass_kg']} kg (planned {task.peg.mass:.6g})")
    if not same(row["peg_length_mm"], task.peg.length * 1000.0):
        problems.append(f"peg length {row['peg_length_mm']} mm (planned "
                        f"{task.peg.length * 1000.0:.6g})")
    if problems:
        raise CorruptFileError(path, f"episode {i} is not this evaluation's ({', '.join(problems)}"
                                     "): rows of another condition, seed or configuration; use "
                                     "a new folder", line=number)
