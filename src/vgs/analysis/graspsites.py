"""Where on the peg each test grasp lay, along its axis and across it (``vgs grasp-sites``).

A position action grasps at the chosen pixel, the jaws closing across the peg's perceived axis
(docs/learning.md). The records give the realised offset along the axis (``grasp_offset_mm``)
but not how far to the side of the axis the chosen pixel lay, on the peg's flank. That is
ground truth recomputed here, for analysis only: a test episode's seed resets the cell to the
scene of the test (:meth:`vgs.assembly.episode.EpisodeRunner.observe`; no physics step), and
with the peg's centre of mass ``p``, its axis projected on the table and normalised, ``a``,
and the table point ``q`` of the decision's pixel ``(row, col)``, the pixel lay

    along_mm  = 1000 a . (q - p)
    across_mm = 1000 |a_x (q - p)_y - a_y (q - p)_x|

from the centre of mass (``along_mm`` signed like the axis the simulator gives the peg,
``across_mm`` unsigned). ``along_mm`` is the commanded offset; the realised
``grasp_offset_mm`` differs from it by what the closing jaws moved the peg (a check of the
recomputation: its median difference is printed). Decisions without a pixel (the centre
heuristic) get NaN.

Tables that record ``across_mm`` (the grasp point's distance from the axis, ground truth) need
no replay: their rows keep ``|across_mm|`` and take ``along_mm`` from the realised
``grasp_offset_mm``; only rows with a pixel and no recorded ``across_mm`` are replayed.
"""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from vgs.analysis.report import load_results
from vgs.assembly.episode import EpisodeRunner, GraspCommand, across_axis_mm
from vgs.checkpoint import atomic_write_text
from vgs.config import ExperimentConfig
from vgs.errors import ConfigError
from vgs.rollout.episodepool import single_blas_thread, stop_pool
from vgs.runfolder.common import read_json
from vgs.runfolder.status import recorded_config

ALONG_EDGES_MM = (0.0, 26.0, 35.0, 40.0, 45.0, np.inf)  # |along_mm| bins of the table
ACROSS_EDGES_MM = (0.0, 5.0, 10.0, np.inf)  # across_mm bins of the table
COLUMNS = ("policy", "condition", "train_run", "seed", "row", "col", "grasp_offset_mm",
           "along_mm", "across_mm", "assembly_success", "failure_reason", "peg_turn_deg")


def folder_config(out: Path) -> ExperimentConfig:
    """The configuration a reproduce folder (or its published copy) recorded.

    Raises:
        ConfigError: If ``out`` holds no ``reproduce.json``.
        CorruptFileError: If the configuration it records is not usable.
    """
    path = out / "reproduce.json"
    if not path.is_file():
        raise ConfigError("grasp-sites", f"{out} is not a reproduce folder (no reproduce.json)")
    return recorded_config(path, read_json(path).get("config"))


def grasp_sites(df: pd.DataFrame, cfg: ExperimentConfig, progress: bool = True,
                workers: int = 1) -> pd.DataFrame:
    """``df``'s test episodes with ``along_mm`` and ``across_mm`` (module docstring).

    Args:
        df: Evaluation rows (``seed``, ``peg_mass_kg``, ``peg_length_mm``, ``row``, ``col``).
        cfg: The configuration the tests ran with (its cell).
        progress: Show a tqdm bar on stderr.
        workers: Processes that reset the scenes (spawned, each with its own cell); 1 = this
            process. Every scene is reset from its seed alone, so the table is the same for
            any number.
    """
    along = np.full(len(df), np.nan)
    across = np.full(len(df), np.nan)
    recorded = np.zeros(len(df), bool)
    if "across_mm" in df.columns:  # the column of the record: no replay for these rows
        across = np.abs(df["across_mm"].to_numpy(float))
        recorded = np.isfinite(across)
        along = np.where(recorded, df["grasp_offset_mm"].to_numpy(float), np.nan)
    rows = df[["seed", "peg_mass_kg", "peg_length_mm", "row", "col"]].itertuples(index=False)
    tasks = [(i, int(seed), float(mass), float(length_mm), int(row), int(col))
             for i, (seed, mass, length_mm, row, col) in enumerate(rows)
             if row >= 0 and col >= 0 and not recorded[i]]
    workers = max(1, min(workers, len(tasks)))
    pool = None
    if not tasks:
        results: Iterator[tuple[int, float, float]] = iter(())
    elif workers == 1:
        _init_worker(cfg)
        results = map(_site, tasks)
    else:
        single_blas_thread()
        pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"),
                                   initializer=_init_worker, initargs=(cfg,))
        results = pool.map(_site, tasks, chunksize=max(1, min(32, len(tasks) // (4 * workers))))
    try:
        for i, a, c in tqdm(results, total=len(tasks), desc="grasp sites", unit="scene",
                            disable=not progress):
            along[i], across[i] = a, c
    except BaseException:  # Ctrl-C, SIGTERM, an error in a worker: stop the workers now
        if pool is not None:
            stop_pool(pool)
        raise
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    sites = df.copy()
    sites["along_mm"], sites["across_mm"] = along, across
    sites = sites[[c for c in COLUMNS if c in sites.columns]]
    sites.attrs["recorded"] = int(recorded.sum())
    return sites


_WORKER: dict[str, Any] = {}  # this process's configuration and episode runner


def _init_worker(cfg: ExperimentConfig) -> None:
    """Give this process (a pool worker, or the command's own) a runner of ``cfg``'s cell."""
    _WORKER.update(cfg=cfg, runner=EpisodeRunner(cfg))


def _site(task: tuple[int, int, float, float, int, int]) -> tuple[int, float, float]:
    """``(index, along_mm, across_mm)`` of one test grasp ``(index, seed, peg mass [kg], peg
    length [mm], row, col)``: its scene reset from the seed, no physics step."""
    i, seed, mass, length_mm, row, col = task
    cfg: ExperimentConfig = _WORKER["cfg"]
    runner: EpisodeRunner = _WORKER["runner"]
    peg = replace(cfg.cell.peg, mass=mass, length=length_mm / 1000)
    hm = runner.observe(seed, peg)
    cell, _ = runner.cell(peg)
    p_world_peg, R_world_peg = cell.peg_pose()
    a = R_world_peg[:2, 2] / np.linalg.norm(R_world_peg[:2, 2])
    x, y = (float(c) for c in hm.pixel_to_world(row, col))
    along = 1000 * float(a @ (np.array([x, y]) - p_world_peg[:2]))
    # The record's own formula for the distance across the axis (one owner).
    return i, along, across_axis_mm(GraspCommand(x, y, 0.0), p_world_peg, R_world_peg)


def sites_table(sites: pd.DataFrame) -> str:
    """Per policy and condition, assembled / tested and the median ``peg_turn_deg`` by
    ``|along_mm|`` (rows) and ``across_mm`` (columns), as Markdown, with the median
    ``across_mm`` and the recomputation's check."""
    lines = []
    along_bins = pd.cut(sites["along_mm"].abs(), ALONG_EDGES_MM, right=False)
    across_bins = pd.cut(sites["across_mm"], ACROSS_EDGES_MM, right=False)
    heads = [_label(b) for b in across_bins.cat.categories]
    for (policy, condition), group in sites.groupby(["policy", "condition"], sort=True):
        picked = group["along_mm"].notna()
        if not picked.any():
            continue
        g = group[picked]
        check = (g["along_mm"].abs() - g["grasp_offset_mm"].abs()).abs().median()
        source = (f"realised offset {check:.1f} mm from the commanded (median)"
                  if not sites.attrs.get("recorded") else
                  "along: the realised offset, across: the recorded `across_mm` (no replay)")
        lines += [f"**{policy}, {condition}**: assembled / tested and the median turn of the "
                  f"peg in the pads (`peg_turn_deg`), {len(g)} grasps at a pixel; "
                  f"median across the axis {g['across_mm'].median():.1f} mm, "
                  f"{100 * (g['across_mm'] >= 10).mean():.0f} % at 10 mm or more; {source}", "",
                  "| along, either side [mm] | " + " | ".join(f"across {h} mm" for h in heads)
                  + " | all |",
                  "|---" * (len(heads) + 2) + "|"]
        for a_bin in along_bins.cat.categories:
            in_a = along_bins[g.index] == a_bin
            cells = [_cell(g[in_a & (across_bins[g.index] == c_bin)])
                     for c_bin in across_bins.cat.categories]
            lines.append(f"| {_label(a_bin)} | " + " | ".join(cells) + f" | {_cell(g[in_a])} |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _label(interval: pd.Interval) -> str:
    if np.isinf(interval.right):
        return f"{interval.left:g}+"
    return f"{interval.left:g}-{interval.right:g}"


def _cell(rows: pd.DataFrame) -> str:
    """``assembled/tested``, and the median turn of the peg in the pads where recorded."""
    if rows.empty:
        return "-"
    text = f"{int(rows['assembly_success'].astype(bool).sum())}/{len(rows)}"
    turn = rows["peg_turn_deg"].median() if "peg_turn_deg" in rows else np.nan
    return text + (f", {turn:.1f} deg" if np.isfinite(turn) else "")


def grasp_sites_report(out: Path, policies: list[str] | None = None,
                       conditions: list[str] | None = None, csv: Path | None = None,
                       progress: bool = True, workers: int = 1) -> str:
    """The table of :func:`sites_table` for the tests in reproduce folder ``out`` (optionally
    some policies and conditions only), the rows written to ``csv`` when given; ``workers``
    processes reset the scenes (:func:`grasp_sites`).

    Raises:
        ConfigError: If ``out`` is no reproduce folder, or the selection is empty.
    """
    cfg = folder_config(out)
    df = load_results(out)
    if policies:
        df = df[df["policy"].isin(policies)]
    if conditions:
        df = df[df["condition"].isin(conditions)]
    if df.empty:
        raise ConfigError("grasp-sites", f"no test episodes in {out} for policies "
                                         f"{policies or 'all'}, conditions {conditions or 'all'}")
    sites = grasp_sites(df.reset_index(drop=True), cfg, progress, workers)
    if csv is not None:
        csv.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(csv, sites.to_csv(index=False, float_format="%.3f"))
    return sites_table(sites)
