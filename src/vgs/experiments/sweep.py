"""Grasp-offset sweep: assemble after grasping at fixed offsets along the peg, in parallel.

A paired experiment (common random numbers): trial ``t`` is one *scene*, the same at every
offset. Its episode seed comes from ``numpy.random.SeedSequence([seed, t])`` and a child of that
sequence draws its peg: ``length = L0 * U(1 - length_range, 1 + length_range)`` and
``mass = m0 * (length / L0) * U(1 - mass_range, 1 + mass_range)`` (the mass follows the volume
when the length changes). So every offset meets the same peg poses, hole displacements, pegs and
sensor noise, and offsets are compared scene by scene (:func:`paired_analysis`). The grasp is
:func:`vgs.assembly.episode.offset_policy`: it sees only the heightmap. Trials run in a
``spawn`` process pool; rows are sorted by trial index, so the result does not depend on the
number of workers. Every finished row is appended to ``journal.jsonl`` in the output folder; a
sweep started again in the same folder checks the journal against its plan and runs only what is
missing.
"""

from __future__ import annotations

import csv
import io
import json
import math
import multiprocessing as mp
import os
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from vgs.analysis.sweepstats import paired_analysis, summarize
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.record import PHASES
from vgs.checkpoint import (
    MAX_JOURNAL_BYTES,
    atomic_write_bytes,
    atomic_write_text,
    open_append,
    read_regular,
)
from vgs.columns import column, normalize_row, rounded_rows
from vgs.config import CellConfig, ExperimentConfig, PegConfig, to_dict
from vgs.errors import ConfigError, CorruptFileError, EpisodeError, RunMismatchError, VGSError
from vgs.jsonsafe import dumps
from vgs.runfolder.common import check_request, host, hosts_of, locked, read_json, write_json
from vgs.runfolder.folderkind import claim
from vgs.runfolder.journal import PUBLISHED, Lines, encode_row, read_lines
from vgs.validate import MAX_EPISODES, check_config

MAX_TRIALS = 100_000  # trials per offset

# The sweep keeps the pad's near edge this far inside the peg's end (pads are 22 mm long).
END_MARGIN = 0.015

# Column vocabulary of vgs.columns (before 2026-12 the peg was mass_kg, length_mm and the
# outcome success: the journal reader renames them).
COLUMNS: tuple[str, ...] = (
    "offset_mm", "peg_mass_kg", "peg_length_mm", "assembly_success", "assembly_time_s",
    *(f"time_{p}_s" for p in PHASES),
    "adjustments", "retries", "failure_reason", "seed", "trial", "grasp_offset_mm",
    "grasp_offset_com_mm", "across_mm", "peg_com_shift_mm",
    "jaw_misalignment_deg", "peg_turn_deg", "peak_grasp_moment_nm", "peak_moment_measured_nm",
    "host_cpu",
    "mujoco_version",
)


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep.

    Attributes:
        offsets: Grasp offsets from the visible peg centre along its axis [m].
        trials: Trials per offset.
        mass_range: Relative half-width of the uniform mass factor.
        length_range: Relative half-width of the uniform length factor.
        seed: Root seed.
    """

    offsets: tuple[float, ...]
    trials: int
    mass_range: float = 0.0
    length_range: float = 0.0
    seed: int = 0


@dataclass(frozen=True)
class Trial:
    """One planned episode."""

    index: int
    offset_index: int
    trial: int
    offset: float
    seed: int
    peg: PegConfig


def shortest_length(nominal: PegConfig, length_range: float) -> float:
    """Shortest peg the length range can draw [m]."""
    return nominal.length * (1.0 - length_range)


def default_offsets(nominal: PegConfig, count: int, length_range: float = 0.0) -> tuple[float, ...]:
    """``count`` offsets evenly spaced over ``+-(L / 2 - 15 mm)`` of the shortest peg [m].

    Raises:
        ConfigError: If ``count`` < 1.
    """
    if count < 1:
        raise ConfigError("offsets", f"need at least one offset, got {count}")
    if count == 1:
        return (0.0,)
    limit = 0.5 * shortest_length(nominal, length_range) - END_MARGIN
    return tuple(float(v) for v in np.linspace(-limit, limit, count))


def check_spec(spec: SweepSpec, cell: CellConfig) -> None:
    """Validate a sweep against the cell's peg.

    Every offset must keep the pads' centre on the shortest peg the length range draws (a
    learned or random policy grasps anywhere on the peg's visible pixels, so the sweep measures
    the whole graspable length; beyond ``L/2 - 11 mm`` the 22 mm pads
    (``vgs.sim.rg2.PAD_HALF``) overhang the peg's end, and whether they still hold is what the
    sweep finds), and the extreme pegs must form valid cells.

    Raises:
        ConfigError: Naming ``offsets``, ``trials``, ``mass_range`` or ``length_range``.
    """
    if isinstance(spec.trials, bool) or not isinstance(spec.trials, int) \
            or not 1 <= spec.trials <= MAX_TRIALS:
        raise ConfigError("trials", f"must be an integer in [1, {MAX_TRIALS}], got "
                                    f"{str(spec.trials)[:40]}")
    if not spec.offsets:
        raise ConfigError("offsets", "no offsets given")
    if len(spec.offsets) * spec.trials > MAX_EPISODES:
        raise ConfigError("trials", f"{len(spec.offsets)} offsets x {spec.trials} trials is more "
                                    f"than {MAX_EPISODES} episodes")
    if not 0.0 <= spec.mass_range < 1.0:
        raise ConfigError("mass_range", f"must lie in [0, 1), got {spec.mass_range}")
    if not 0.0 <= spec.length_range < 1.0:
        raise ConfigError("length_range", f"must lie in [0, 1), got {spec.length_range}")
    peg = cell.peg
    for factor in (1.0 - spec.length_range, 1.0 + spec.length_range):
        try:
            replace(cell, peg=replace(peg, length=peg.length * factor))
        except ConfigError as exc:
            raise ConfigError("length_range", f"gives an invalid peg ({exc})") from exc
    limit = 0.5 * shortest_length(peg, spec.length_range)
    for offset in spec.offsets:
        if not (math.isfinite(offset) and abs(offset) <= limit + 1e-12):
            raise ConfigError(
                "offsets",
                f"{offset * 1000:g} mm is off the peg: the pads' centre stays on it for "
                f"|offset| <= {limit * 1000:.1f} mm",
            )


def plan(spec: SweepSpec, nominal: PegConfig) -> list[Trial]:
    """All trials of the sweep, in index order (offset-major)."""
    trials = []
    for i, offset in enumerate(spec.offsets):
        for t in range(spec.trials):
            seq = np.random.SeedSequence([spec.seed, t])  # the scene: the same at every offset
            seed = int(seq.generate_state(1)[0])
            rng = np.random.default_rng(seq.spawn(1)[0])
            length_factor = rng.uniform(1.0 - spec.length_range, 1.0 + spec.length_range)
            mass_factor = rng.uniform(1.0 - spec.mass_range, 1.0 + spec.mass_range)
            peg = nominal
            if spec.length_range > 0 or spec.mass_range > 0:
                peg = replace(nominal, length=nominal.length * length_factor,
                              mass=nominal.mass * length_factor * mass_factor)
            trials.append(Trial(index=len(trials), offset_index=i, trial=t, offset=offset,
                                seed=seed, peg=peg))
    return trials


_RUNNER: EpisodeRunner | None = None


def _init_worker(cfg: ExperimentConfig) -> None:
    global _RUNNER
    _RUNNER = EpisodeRunner(cfg)


def _run_trial(trial: Trial) -> tuple[int, dict[str, Any]]:
    if _RUNNER is None:
        raise VGSError("sweep worker used before its initialisation")
    try:
        record, _, _ = _RUNNER.run(trial.seed, offset_policy(trial.offset), peg=trial.peg)
    except Exception as exc:  # noqa: BLE001 - a bug is not a result: the sweep stops
        message = " ".join(str(exc).split())[:200]
        raise EpisodeError(f"sweep trial {trial.index} (offset {trial.offset * 1000:g} mm, seed "
                           f"{trial.seed}) raised {type(exc).__name__}: {message}; the journal "
                           "keeps the trials finished before it") from None
    # The record's row gives every column but the sweep's own (the peg of the record is the
    # trial's); the host too: MuJoCo's floating point differs between CPUs.
    row = {**record.to_row(), "offset_mm": trial.offset * 1000.0, "trial": trial.trial,
           **host()}
    return trial.index, {k: row[k] for k in COLUMNS}


def run_sweep(cfg: ExperimentConfig, spec: SweepSpec, workers: int | None = None,
              progress: bool = True, journal: Path | None = None,
              done: dict[int, dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Run every trial of ``spec`` and return one row per trial, sorted by trial index.

    Args:
        cfg: Experiment configuration (cell, controller, assembly).
        spec: The sweep.
        workers: Worker processes (default ``os.cpu_count()``); 1 runs in this process.
        progress: Show a tqdm bar on stderr.
        journal: A JSON-lines file: rows found there (checked against the plan) are not run
            again, and every new row is appended to it as it arrives.
        done: The journal's rows, already read (:func:`sweep_to_folder`); None reads them.

    Raises:
        ConfigError: If the sweep or the worker count is invalid.
        VGSError: If the journal holds a row that the plan does not (another sweep's folder).
    """
    check_spec(spec, cfg.cell)
    workers = (os.cpu_count() or 1) if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError("workers", f"must be an integer >= 1, got {workers!r}")
    trials = plan(spec, cfg.cell.peg)
    if done is not None:
        rows = dict(done)
    else:
        rows = read_journal(journal, trials) if journal is not None else {}
    todo = [t for t in trials if t.index not in rows]
    bar = tqdm(total=len(trials), initial=len(rows), desc="sweep", unit="episode",
               disable=not progress)
    with bar, _appender(journal) as write:
        if todo:
            for index, row in _results(cfg, todo, min(workers, len(todo))):
                rows[index] = row
                write({"index": index, **row})
                bar.update(1)
    return [rows[i] for i in sorted(rows)]


def read_journal(path: Path, trials: Sequence[Trial], legacy: Collection[str] = PUBLISHED,
                 any_legacy: bool = False) -> dict[int, dict[str, Any]]:
    """Rows of an earlier run of the same sweep, by trial index (:func:`read_sweep_journal`)."""
    return read_sweep_journal(path, trials, legacy, any_legacy)[0]


def read_sweep_journal(path: Path, trials: Sequence[Trial], legacy: Collection[str] = PUBLISHED,
                       any_legacy: bool = False) -> tuple[dict[int, dict[str, Any]], Lines]:
    """Rows of an earlier run of the same sweep, by trial index, and the journal's lines.

    The journal's integrity rule is every journal's (:func:`vgs.runfolder.journal.read_lines`:
    a checksum on every row but the recorded leading rows written before it; a torn last line
    is dropped). Each row must be the plan's trial of its index (offset, seed, peg), and no
    index may come twice.

    Raises:
        CorruptFileError: Naming the file and line of a row the plan does not hold, a
            duplicate, a changed row or one without its checksum.
    """
    rows: dict[int, dict[str, Any]] = {}
    found = read_lines(path, legacy, any_legacy)
    first: dict[int, int] = {}
    for n, doc in found.rows:
        index = doc.pop("index", None)
        if isinstance(index, bool) or not isinstance(index, int) \
                or not 0 <= index < len(trials):
            raise CorruptFileError(path, f"is a row of another sweep (index {index!r}); use "
                                         "another --out or remove the file", line=n)
        if index in first:
            raise CorruptFileError(path, f"repeats trial {index} (first at line "
                                         f"{first[index]}); restore the journal or use a new "
                                         "folder", line=n)
        t = trials[index]
        doc = normalize_row(doc)  # legacy names renamed, null floats back to NaN
        expected = (round(t.offset * 1000.0, 6), t.seed, round(t.peg.mass, 9),
                    round(t.peg.length * 1000.0, 6))
        found_key = (round(_number(doc.get("offset_mm")), 6), doc.get("seed"),
                     round(_number(doc.get("peg_mass_kg")), 9),
                     round(_number(doc.get("peg_length_mm")), 6))
        if found_key != expected:
            raise CorruptFileError(path, "is a row of another sweep (offset, seed or peg differ "
                                         "from this sweep's plan); use another --out or remove "
                                         "the file", line=n)
        first[index] = n
        rows[index] = {k: (math.nan if doc.get(k) is None and column(k).kind == "float"
                           else doc.get(k)) for k in COLUMNS}
    return rows, found


def _number(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


@contextmanager
def _appender(path: Path | None) -> Iterator[Callable[[dict[str, Any]], None]]:
    """A function that appends one strict-JSON row to the journal ``path`` (none: drops it)."""
    if path is None:
        yield lambda row: None
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with open_append(path) as fh:
        def write(row: dict[str, Any]) -> None:
            fh.write(encode_row(row))
            fh.flush()

        yield write


def _results(cfg: ExperimentConfig, trials: list[Trial],
             workers: int) -> Iterable[tuple[int, dict[str, Any]]]:
    if workers == 1:
        _init_worker(cfg)
        yield from map(_run_trial, trials)
        return
    ctx = mp.get_context("spawn")
    with ctx.Pool(workers, initializer=_init_worker, initargs=(cfg,)) as pool:
        yield from pool.imap_unordered(_run_trial, trials, chunksize=1)


def write_csv(rows: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Write the sweep rows with :data:`COLUMNS`."""
    path = Path(path)
    buffer = io.StringIO(newline="")
    writer = csv.DictWriter(buffer, fieldnames=list(COLUMNS))
    writer.writeheader()
    writer.writerows(rounded_rows(rows))  # times to the ms
    atomic_write_text(path, buffer.getvalue())
    return path


def sweep_to_folder(cfg: ExperimentConfig, spec: SweepSpec, out: Path,
                    workers: int | None = None, progress: bool = True) -> list[dict[str, Any]]:
    """Run (or resume) the sweep in ``out``, locked; write ``out/sweep.json`` (what the sweep
    is: its plan and configuration, checked on resume), ``out/journal.jsonl`` as trials end,
    then ``out/sweep.csv``, ``out/sweep.png`` and ``out/summary.json``.

    A folder written before ``sweep.json`` existed is resumed once under the legacy rule: its
    journal's rows without checksums are accepted (still checked against the plan) and their
    SHA-256 is recorded in ``sweep.json`` (``legacy_rows``), so that from then on only those
    rows may lack a checksum.

    Returns:
        The per-offset summary (:func:`summarize`).

    Raises:
        RunMismatchError: If ``out`` holds another kind of folder or another sweep.
        CorruptFileError: If ``sweep.json`` or the journal cannot be read or holds rows of
            another sweep, duplicates or rows without checksums.
        FolderBusyError: If another process works in ``out``.
    """
    from vgs.analysis.sweepfigure import sweep_figure

    cfg = check_config(cfg)  # before anything is written
    check_spec(spec, cfg.cell)
    claim(out, "sweep")
    out.mkdir(parents=True, exist_ok=True)
    with locked(out):
        done = _prepare(cfg, spec, out)
        rows = run_sweep(cfg, spec, workers=workers, progress=progress,
                         journal=out / "journal.jsonl", done=done)
        write_csv(rows, out / "sweep.csv")
        ranges = (f"mass +-{100 * spec.mass_range:g} %, length +-{100 * spec.length_range:g} %"
                  if spec.mass_range or spec.length_range else "nominal peg")
        summary = summarize(rows)
        for name in ("sweep.png", ".sweep.png.tmp"):  # never drawn through a planted link
            if (out / name).is_symlink():
                (out / name).unlink()
        sweep_figure(rows, summary, cfg, out / "sweep.png",
                     title=f"{len(rows)} episodes, {spec.trials} per offset, {ranges}")
        doc = {"profile": cfg.name, "seed": spec.seed, "trials": spec.trials,
               "mass_range": spec.mass_range, "length_range": spec.length_range,
               "offsets": summary, "paired": paired_analysis(rows), "hosts": hosts_of(rows)}
        atomic_write_text(out / "summary.json", dumps(doc, indent=2) + "\n")
    return summary


def _prepare(cfg: ExperimentConfig, spec: SweepSpec, out: Path) -> dict[int, dict[str, Any]]:
    """Check ``out/sweep.json`` against the request (or write it) and the journal against the
    plan; return the journal's rows. Call with ``out`` locked."""
    meta_path, journal = out / "sweep.json", out / "journal.jsonl"
    request = {"offsets": list(spec.offsets), "trials": spec.trials,
               "mass_range": spec.mass_range, "length_range": spec.length_range,
               "seed": spec.seed}
    legacy: dict[str, Any] | None = None
    if meta_path.exists() or meta_path.is_symlink():
        old = read_json(meta_path)
        recorded = old.get("spec")
        if not isinstance(recorded, dict) or not isinstance(old.get("config"), dict):
            raise CorruptFileError(meta_path, "records no sweep plan and configuration")
        for key, value in request.items():
            if json.dumps(recorded.get(key)) != json.dumps(value):
                raise RunMismatchError(key, f"{out} holds another sweep ({recorded.get(key)!r}, "
                                            f"not {value!r}); use a new folder")
        check_request(old["config"], cfg, meta_path)
        legacy = old.get("legacy_rows") if isinstance(old.get("legacy_rows"), dict) else None
        known = set(PUBLISHED) | ({str(legacy.get("sha256"))} if legacy else set())
        rows, lines = read_sweep_journal(journal, plan(spec, cfg.cell.peg), known)
    else:  # a new folder, or one written before sweep.json: its rows are recorded now
        rows, lines = read_sweep_journal(journal, plan(spec, cfg.cell.peg), any_legacy=True)
        legacy = lines.legacy
    write_json(meta_path, {"kind": "sweep", "spec": request, "config": to_dict(cfg),
                           "legacy_rows": legacy})
    if lines.cut or lines.unterminated:  # drop a torn line / end the last one (the others
        data = read_regular(journal, MAX_JOURNAL_BYTES)  # as written: their digests hold)
        atomic_write_bytes(journal, data[:data.rfind(b"\n") + 1] if lines.cut else data + b"\n")
    return rows
