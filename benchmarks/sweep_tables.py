"""Markdown tables of a `vgs sweep` folder, as docs/assembly.md shows them.

Reads ``summary.json`` and ``sweep.csv`` of the folder and prints:

* per offset: assembled, mean / std of the time of assembled pegs, alignment time, the share of
  episodes with at least one new search, the peg's turn in the pads (median / max) and the
  median peak moment on the grasp (ground truth, analysis only);
* the totals: assembled, failures by reason, re-search share, coefficient of variation of the
  time of assembled pegs, ``not_inserted`` rows;
* the paired differences against the centre grasp with their 95 % intervals, the slope of the
  time against |offset|, and the +c / -c comparison (all from ``summary.json``).

Usage::

    python benchmarks/sweep_tables.py docs/results/cell_touchdown/sweep
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import sys
from pathlib import Path

import numpy as np

from vgs.columns import as_bool, normalize_row
from vgs.experiments.stats import population_std


def _rows(folder: Path) -> list[dict[str, str]]:
    """The sweep's rows, legacy column names renamed (vgs.columns)."""
    with open(folder / "sweep.csv", newline="") as f:
        return [normalize_row(row) for row in csv.DictReader(f)]


def _true(value: object) -> bool:
    return bool(as_bool(value))


def per_offset(folder: Path) -> str:
    """The per-offset table: the sweep's own statistics (``summary.json``, made by
    :func:`vgs.experiments.sweepstats.summarize`) beside the analysis-only columns of its rows."""
    rows = _rows(folder)
    by_offset: dict[float, list[dict[str, str]]] = collections.defaultdict(list)
    for r in rows:
        by_offset[float(r["offset_mm"])].append(r)
    out = ["| offset [mm] | assembled | mean time [s] | std [s] | alignment [s] | re-search "
           "| peg turn in pads, median / max [deg] | peak grasp moment, median [N m] |",
           "|---|---|---|---|---|---|---|---|"]
    for stat in json.loads((folder / "summary.json").read_text())["offsets"]:
        group = by_offset[float(stat["offset_mm"])]
        turn = np.array([float(r["peg_turn_deg"]) for r in group])
        peak = np.array([float(r["peak_grasp_moment_nm"]) for r in group])
        out.append(f"| {stat['offset_mm']:+.1f} | {stat['successes']}/{stat['n']} | "
                   f"{stat['time_mean_s']:.1f} | {stat['time_std_s']:.1f} | "
                   f"{stat['time_align_mean_s']:.1f} | {100 * stat['retry_rate']:.0f} % | "
                   f"{np.median(turn):.1f} / {turn.max():.1f} | {np.median(peak):.2f} |")
    ok = [r for r in rows if _true(r["assembly_success"])]
    t = np.array([float(r["assembly_time_s"]) for r in ok])
    fails = collections.Counter(r["failure_reason"] for r in rows
                                if not _true(r["assembly_success"]))
    retry = np.mean([int(float(r["retries"])) > 0 for r in rows])
    fail_text = ", ".join(f"{n} `{k}`" for k, n in fails.most_common()) or "none"
    out.append("")
    share = 100 * len(ok) / len(rows)
    # The sweep summary's standard deviation convention (vgs.experiments.stats).
    cv = population_std(t) / t.mean()
    out.append(f"All offsets: {len(ok)}/{len(rows)} assembled ({share:.1f} %); "
               f"failures: {fail_text}; re-search in {100 * retry:.0f} % of episodes; CV "
               f"(std / mean) of successful times {cv:.2f}; "
               f"`not_inserted`: {fails.get('not_inserted', 0)}")
    return "\n".join(out)


def _share(d: dict, side: str) -> str:
    k, n = d[f"{side}_success"]
    lo, hi = d[f"{side}_success_ci"]
    return f"{k}/{n} ({100 * lo:.0f}-{100 * hi:.0f} %)"


def _time(d: dict, side: str) -> str:
    lo, hi = d[f"{side}_time_ci_s"]
    return f"{d[f'{side}_time_s']:.1f} ({lo:.1f}-{hi:.1f})"


def paired(folder: Path) -> str:
    paired = json.loads((folder / "summary.json").read_text())["paired"]
    out = ["| offset [mm] | pairs | T - T(0) [s], 95 % CI "
           "| alignment - alignment(0) [s], 95 % CI |", "|---|---|---|---|"]
    for d in paired["vs_center"]:
        lo, hi = d["time_diff_ci_s"]
        alo, ahi = d["align_diff_ci_s"]
        out.append(f"| {d['offset_mm']:+.1f} | {d['pairs']} | {d['time_diff_s']:+.1f} "
                   f"[{lo:+.1f}, {hi:+.1f}] | {d['align_diff_s']:+.1f} [{alo:+.1f}, {ahi:+.1f}] |")
    s = paired["slope"]
    out.append("")
    out.append(f"Slope against |offset| (successful rows, 95 % interval from resampling scenes): "
               f"time {s['time_s_per_mm']:+.3f} s/mm [{s['time_ci_s_per_mm'][0]:+.3f}, "
               f"{s['time_ci_s_per_mm'][1]:+.3f}]; alignment time {s['align_s_per_mm']:+.3f} "
               f"[{s['align_ci_s_per_mm'][0]:+.3f}, {s['align_ci_s_per_mm'][1]:+.3f}] s/mm")
    out.append("")
    out.append("| abs offset [mm] | +c assembled (95 % CI) | -c assembled (95 % CI) "
               "| +c mean time [s] (CI) | -c mean time [s] (CI) |")
    out.append("|---|---|---|---|---|")
    for d in paired["symmetry"]:
        out.append(f"| {d['abs_offset_mm']:.1f} | {_share(d, 'plus')} | {_share(d, 'minus')} | "
                   f"{_time(d, 'plus')} | {_time(d, 'minus')} |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="a vgs sweep output folder")
    args = ap.parse_args(argv)
    if not (args.folder / "summary.json").is_file():
        print(f"{args.folder}: no summary.json (not a finished vgs sweep folder)",
              file=sys.stderr)
        return 2
    print(per_offset(args.folder))
    summary = json.loads((args.folder / "summary.json").read_text())
    if summary.get("paired", {}).get("vs_center"):
        print()
        print(paired(args.folder))
    return 0


if __name__ == "__main__":
    sys.exit(main())
