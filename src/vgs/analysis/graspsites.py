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

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from vgs.analysis.report import load_results
from vgs.assembly.episode import EpisodeRunner
from vgs.checkpoint import atomic_write_text
from vgs.config import ExperimentConfig
from vgs.errors import ConfigError
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


def grasp_sites(df: pd.DataFrame, cfg: ExperimentConfig, progress: bool = True
                ) -> pd.DataFrame:
    """``df``'s test episodes with ``along_mm`` and ``across_mm`` (module docstring).

    Args:
        df: Evaluation rows (``seed``, ``peg_mass_kg``, ``peg_length_mm``, ``row``, ``col``).
        cfg: The configuration the tests ran with (its cell).
        progress: Show a tqdm bar on stderr.
    """
    along = np.full(len(df), np.nan)
    across = np.full(len(df), np.nan)
    recorded = np.zeros(len(df), bool)
    if "across_mm" in df.columns:  # the column of the record: no replay for these rows
        across = np.abs(df["across_mm"].to_numpy(float))
        recorded = np.isfinite(across)
        along = np.where(recorded, df["grasp_offset_mm"].to_numpy(float), np.nan)
    replay = np.flatnonzero(~recorded & (df["row"].to_numpy() >= 0)
                            & (df["col"].to_numpy() >= 0))
    runner = EpisodeRunner(cfg) if replay.size else None
    rows = df[["seed", "peg_mass_kg", "peg_length_mm", "row", "col"]].to_numpy()
    for i in tqdm(replay, desc="grasp sites", unit="scene", disable=not progress):
        seed, mass, length_mm, row, col = rows[i]
        assert runner is not None
        peg = replace(cfg.cell.peg, mass=float(mass), length=float(length_mm) / 1000)
        hm = runner.observe(int(seed), peg)
        cell, _ = runner.cell(peg)
        p_world_peg, R_world_peg = cell.peg_pose()
        a = R_world_peg[:2, 2] / np.linalg.norm(R_world_peg[:2, 2])
        q = np.asarray(hm.pixel_to_world(int(row), int(col)), dtype=float)
        v = q - p_world_peg[:2]
        along[i] = 1000 * float(a @ v)
        across[i] = 1000 * abs(float(a[0] * v[1] - a[1] * v[0]))
    sites = df.copy()
    sites["along_mm"], sites["across_mm"] = along, across
    sites = sites[[c for c in COLUMNS if c in sites.columns]]
    sites.attrs["recorded"] = int(recorded.sum())
    return sites


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
                       progress: bool = True) -> str:
    """The table of :func:`sites_table` for the tests in reproduce folder ``out`` (optionally
    some policies and conditions only), the rows written to ``csv`` when given.

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
    sites = grasp_sites(df.reset_index(drop=True), cfg, progress)
    if csv is not None:
        csv.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(csv, sites.to_csv(index=False, float_format="%.3f"))
    return sites_table(sites)
