"""Grasp-offset sweep: assemble after grasping at fixed offsets along the peg, in parallel.

For each offset ``o_i`` and trial ``t`` the episode seed comes from
``numpy.random.SeedSequence([seed, i, t])``; a child of that sequence draws the peg of the trial:
``length = L0 * U(1 - length_range, 1 + length_range)`` and
``mass = m0 * (length / L0) * U(1 - mass_range, 1 + mass_range)`` (the mass follows the volume
when the length changes). The grasp is :func:`vgs.assembly.episode.offset_policy`: it sees only
the heightmap. Trials run in a ``spawn`` process pool; rows are sorted by trial index, so the
result does not depend on the number of workers.
"""

from __future__ import annotations

import csv
import math
import multiprocessing as mp
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.record import PHASES
from vgs.config import CellConfig, ExperimentConfig, PegConfig
from vgs.errors import ConfigError, VGSError
from vgs.jsonsafe import json_safe
from vgs.sim.rg2 import PAD_HALF

GRAVITY = 9.81
# The sweep keeps the pad's near edge this far inside the peg's end (pads are 22 mm long).
END_MARGIN = 0.015

COLUMNS: tuple[str, ...] = (
    "offset_mm", "mass_kg", "length_mm", "success", "assembly_time_s",
    *(f"time_{p}_s" for p in PHASES),
    "adjustments", "failure_reason", "seed", "grasp_offset_mm",
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

    Every offset must keep both pads (22 mm long) on the shortest peg the length range draws,
    and the extreme pegs must form valid cells.

    Raises:
        ConfigError: Naming ``offsets``, ``trials``, ``mass_range`` or ``length_range``.
    """
    if spec.trials < 1:
        raise ConfigError("trials", f"must be >= 1, got {spec.trials}")
    if not spec.offsets:
        raise ConfigError("offsets", "no offsets given")
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
    limit = 0.5 * shortest_length(peg, spec.length_range) - PAD_HALF[0]
    for offset in spec.offsets:
        if not (math.isfinite(offset) and abs(offset) <= limit + 1e-12):
            raise ConfigError(
                "offsets",
                f"{offset * 1000:g} mm is off the peg: the pads stay on it for |offset| <= "
                f"{limit * 1000:.1f} mm",
            )


def plan(spec: SweepSpec, nominal: PegConfig) -> list[Trial]:
    """All trials of the sweep, in index order (offset-major)."""
    trials = []
    for i, offset in enumerate(spec.offsets):
        for t in range(spec.trials):
            seq = np.random.SeedSequence([spec.seed, i, t])
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
    record, _, _ = _RUNNER.run(trial.seed, offset_policy(trial.offset), peg=trial.peg)
    row = record.to_row()
    out = {
        "offset_mm": trial.offset * 1000.0,
        "mass_kg": trial.peg.mass,
        "length_mm": trial.peg.length * 1000.0,
        "success": bool(row["success"]),
        "assembly_time_s": row["assembly_time"],
        **{f"time_{p}_s": row[f"time_{p}_s"] for p in PHASES},
        "adjustments": row["adjustments"],
        "failure_reason": row["failure_reason"],
        "seed": trial.seed,
        "grasp_offset_mm": row["grasp_offset_mm"],
    }
    return trial.index, out


def run_sweep(cfg: ExperimentConfig, spec: SweepSpec, workers: int | None = None,
              progress: bool = True) -> list[dict[str, Any]]:
    """Run every trial of ``spec`` and return one row per trial, sorted by trial index.

    Args:
        cfg: Experiment configuration (cell, controller, assembly).
        spec: The sweep.
        workers: Worker processes (default ``os.cpu_count()``); 1 runs in this process.
        progress: Show a tqdm bar on stderr.

    Raises:
        ConfigError: If the sweep or the worker count is invalid.
    """
    check_spec(spec, cfg.cell)
    workers = (os.cpu_count() or 1) if workers is None else workers
    if workers < 1:
        raise ConfigError("workers", f"must be >= 1, got {workers}")
    trials = plan(spec, cfg.cell.peg)
    rows: dict[int, dict[str, Any]] = {}
    bar = tqdm(total=len(trials), desc="sweep", unit="episode", disable=not progress)
    with bar:
        for index, row in _results(cfg, trials, min(workers, len(trials))):
            rows[index] = row
            bar.update(1)
    return [rows[i] for i in sorted(rows)]


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
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(COLUMNS))
        writer.writeheader()
        writer.writerows(rows)
    return path


def sweep_to_folder(cfg: ExperimentConfig, spec: SweepSpec, out: Path,
                    workers: int | None = None, progress: bool = True) -> list[dict[str, Any]]:
    """Run the sweep and write ``out/sweep.csv``, ``out/sweep.png`` and ``out/summary.json``.

    Returns:
        The per-offset summary (:func:`summarize`).
    """
    import json

    from vgs.experiments.plots import sweep_figure

    rows = run_sweep(cfg, spec, workers=workers, progress=progress)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "sweep.csv")
    ranges = (f"mass +-{100 * spec.mass_range:g} %, length +-{100 * spec.length_range:g} %"
              if spec.mass_range or spec.length_range else "nominal peg")
    sweep_figure(rows, cfg, out / "sweep.png",
                 title=f"{len(rows)} episodes, {spec.trials} per offset, {ranges}")
    summary = summarize(rows)
    doc = {"profile": cfg.name, "seed": spec.seed, "trials": spec.trials,
           "mass_range": spec.mass_range, "length_range": spec.length_range,
           "offsets": summary}
    (out / "summary.json").write_text(json.dumps(json_safe(doc), indent=2) + "\n")
    return summary


def _stat(values: np.ndarray, fn: Any) -> float | None:
    return float(fn(values)) if values.size else None


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per offset: trials, success rate and the mean/std/min/max time of successful trials."""
    out = []
    for offset in sorted({r["offset_mm"] for r in rows}):
        group = [r for r in rows if r["offset_mm"] == offset]
        times = np.array([r["assembly_time_s"] for r in group if r["success"]], dtype=float)
        out.append({
            "offset_mm": offset,
            "n": len(group),
            "successes": int(times.size),
            "success_rate": times.size / len(group),
            "time_mean_s": _stat(times, np.mean),
            "time_std_s": _stat(times, np.std),
            "time_min_s": _stat(times, np.min),
            "time_max_s": _stat(times, np.max),
            "adjustments_mean": float(np.mean([r["adjustments"] for r in group])),
        })
    return out


def disturbing_moments(cfg: ExperimentConfig, lever: np.ndarray,
                       mass: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Paper eq. 2 and 3 for the grasp lever arms ``lever`` [m].

    ``M_G = m g |l| sin(beta)`` with beta the search tilt ``assembly.search_tilt_deg`` (the
    angle between gravity and the peg axis that the controller holds), and
    ``M_I = (1/2) m r^2 d2beta/dt2`` with ``r = |l|`` and the peak angular acceleration of a
    sinusoidal wiggle of amplitude A and period T: ``(2 pi / T)^2 A``.

    Args:
        cfg: Experiment configuration (assembly settings, nominal peg mass).
        lever: Distances from the pads to the centre of mass [m].
        mass: Peg mass [kg]; default the configured one.

    Returns:
        ``(M_G, M_I)`` in N m.
    """
    m = cfg.cell.peg.mass if mass is None else mass
    a = cfg.assembly
    lever = np.abs(np.asarray(lever, dtype=float))
    m_g = m * GRAVITY * lever * math.sin(math.radians(a.search_tilt_deg))
    accel = (2.0 * math.pi / a.wiggle_period) ** 2 * math.radians(a.wiggle_amplitude_deg)
    m_i = 0.5 * m * lever**2 * accel
    return m_g, m_i
