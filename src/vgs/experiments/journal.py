"""An evaluation's ``journal.jsonl``: one JSON row per finished episode, appended as it ends.

Each line is strict JSON (NaN as ``null``) in the column vocabulary of :mod:`vgs.columns` and
carries ``crc32``, the CRC-32 of the row's JSON without it (:func:`encode_row`), so a row changed
after it was written is caught; rows of journals written before it existed have none and are
taken as they are. Rows written before the vocabulary (legacy names such as ``peg_mass``,
``success``, bare ``NaN``) are read too: the checksum is checked on the row as written, then the
row is put in the vocabulary (:func:`vgs.columns.normalize_row`).

Read back with checks (torch-, pandas- and MuJoCo-free, so ``vgs status`` stays quick): every
line must be UTF-8 JSON holding an episode row whose checksum matches; no index may come twice;
with the plan given, each row must be the planned episode of its index (episode seed, peg mass
and length). The one exception is the last line when a kill cut it short (no JSON): it is
dropped and its episode runs again.
"""

from __future__ import annotations

import json
import math
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from vgs.columns import normalize_row
from vgs.errors import CorruptFileError
from vgs.jsonsafe import dumps


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
    whether a cut last line was dropped.

    Args:
        path: The journal.
        plan: The planned episodes (:class:`vgs.experiments.evaluate.EpisodeTask`); each
            row must match the episode of its index (episode seed, peg mass and length).
            None checks the rows' form only (``vgs status``).

    Raises:
        CorruptFileError: Naming the file and line of a line that is not UTF-8, not JSON (but
            for the last line when a kill cut it short), not an episode row, a duplicate, or a
            row of another plan.
    """
    rows: dict[int, dict[str, Any]] = {}
    cut = False
    required = ROW_KEYS if plan is not None else ("index", "assembly_success")
    if not path.exists():
        return rows, cut
    data = path.read_bytes()
    lines = data.split(b"\n")
    first: dict[int, int] = {}
    for number, raw in enumerate(lines, start=1):
        last = number == len(lines)
        if not raw.strip():
            if last:
                continue
            raise CorruptFileError(path, "is an empty line, not an episode row", line=number)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise CorruptFileError(path, "is not UTF-8 text; restore the journal or use a new "
                                         "folder", line=number) from None
        try:
            row = json.loads(text)
        except json.JSONDecodeError:
            if last:  # a line cut short by a kill: its episode runs again
                cut = True
                continue
            raise CorruptFileError(path, "is not a JSON line; restore the journal or use a new "
                                         "folder", line=number) from None
        if isinstance(row, dict) and "crc32" in row:
            crc = row.pop("crc32")
            # Python's JSON of the parsed row is the text written: null stays null, and the bare
            # NaN of journals written before strict JSON stays NaN.
            if crc != zlib.crc32(json.dumps(row).encode()):
                raise CorruptFileError(path, "was changed after it was written (its checksum "
                                             "does not match); restore the journal or use a new "
                                             "folder", line=number)
        if isinstance(row, dict):
            row = normalize_row(row)
        if not isinstance(row, dict) or any(k not in row for k in required) \
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
    return rows, cut


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
