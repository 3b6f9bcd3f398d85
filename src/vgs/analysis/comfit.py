"""Does the grasp act through the centre of mass or through the peg's geometry? (issue 55)

Two sweeps of ``vgs sweep`` on the same scenes and offsets: a peg whose centre of mass lies
``c`` from its middle (``--set cell.peg.com_shift_mm=c``) and its uniform twin. The heavy end
points wherever the scene's random yaw turns it, so a commanded offset lands on either side of
the centre of mass; the records hold both ground-truth distances of the grasp, from the middle
``d_m = |grasp_offset_mm|`` and from the centre of mass ``d_c = |grasp_offset_com_mm|``. On the
shifted peg they differ, and the successful trials within ``MAX_FIT_MM`` of the middle are
fitted jointly by least squares,

    t = b0 + b_m d_m + b_c d_c,

for the assembly time and for the alignment phase alone, each coefficient with a 95 % bootstrap
interval over scenes (every offset of a drawn scene together). Through the mass (paper eq. 2-3)
means ``b_c`` above zero and ``b_m`` not; through the geometry (where the pads sit on the peg)
the reverse. The uniform twin (``d_c = d_m``) gives the single slope ``t = a0 + a d``. Beside
the fit, per offset, the shifted peg against its twin on the same scenes: assembled / trials
and the mean paired time difference of the scenes both assembled.

Ground truth for analysis only; nothing here reaches the controller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from vgs.analysis.stats import BOOTSTRAP_RESAMPLES

MAX_FIT_MM = 35.0  # the fit's range of |offset from the middle|: the pads overhang beyond ~39
FIT_TARGETS = (("assembly_time_s", "assembly"), ("time_align_s", "alignment"))


@dataclass(frozen=True)
class Fit:
    """Least-squares coefficients with their 95 % bootstrap intervals over scenes."""

    names: tuple[str, ...]
    values: tuple[float, ...]
    lows: tuple[float, ...]
    highs: tuple[float, ...]
    n: int

    def as_dict(self) -> dict[str, Any]:
        return {"n": self.n, **{name: {"value": v, "ci95": [lo, hi]} for name, v, lo, hi in
                                zip(self.names, self.values, self.lows, self.highs,
                                    strict=True)}}


def _design(df: pd.DataFrame, joint: bool) -> np.ndarray:
    d_m = df["grasp_offset_mm"].abs().to_numpy(float)
    columns = [np.ones_like(d_m), d_m]
    if joint:
        columns.append(df["grasp_offset_com_mm"].abs().to_numpy(float))
    return np.stack(columns, axis=1)


def fit(df: pd.DataFrame, target: str, joint: bool, resamples: int = BOOTSTRAP_RESAMPLES,
        seed: int = 0) -> Fit:
    """``target ~ 1 + d_m (+ d_c)`` on the successful trials of ``df`` within
    :data:`MAX_FIT_MM`, with scenes (``trial``) resampled for the intervals."""
    ok = df[df["assembly_success"].astype(bool)
            & (df["grasp_offset_mm"].abs() <= MAX_FIT_MM)].reset_index(drop=True)
    names = ("intercept_s", "per_mm_from_middle_s", "per_mm_from_com_s")[:3 if joint else 2]
    if len(ok) < len(names) + 2:
        nan = (math.nan,) * len(names)
        return Fit(names, nan, nan, nan, len(ok))
    X, y = _design(ok, joint), ok[target].to_numpy(float)
    beta = np.linalg.lstsq(X, y, rcond=None)[0]
    rng = np.random.default_rng(seed)
    scenes = ok["trial"].to_numpy()
    unique = np.unique(scenes)
    rows_of = {s: np.flatnonzero(scenes == s) for s in unique}
    draws = []
    for _ in range(resamples):
        pick = np.concatenate([rows_of[s] for s in rng.choice(unique, unique.size)])
        draws.append(np.linalg.lstsq(X[pick], y[pick], rcond=None)[0])
    lo, hi = np.percentile(np.array(draws), [2.5, 97.5], axis=0)
    return Fit(names, tuple(map(float, beta)), tuple(map(float, lo)), tuple(map(float, hi)),
               len(ok))


def paired_by_offset(shifted: pd.DataFrame, twin: pd.DataFrame) -> list[dict[str, Any]]:
    """Per commanded offset: assembled / trials of each peg and the mean time difference
    (shifted minus twin) over the scenes both assembled."""
    key = ["offset_mm", "trial"]
    both = shifted.merge(twin, on=key, suffixes=("", "_twin"))
    out = []
    for offset, g in both.groupby("offset_mm"):
        ok = g["assembly_success"].astype(bool) & g["assembly_success_twin"].astype(bool)
        diff = (g.loc[ok, "assembly_time_s"] - g.loc[ok, "assembly_time_s_twin"]).to_numpy()
        out.append({"offset_mm": float(offset), "trials": len(g),
                    "assembled": int(g["assembly_success"].astype(bool).sum()),
                    "assembled_twin": int(g["assembly_success_twin"].astype(bool).sum()),
                    "time_diff_mean_s": float(diff.mean()) if diff.size else math.nan,
                    "median_grasp_offset_com_mm": float(g["grasp_offset_com_mm"].abs()
                                                        .median())})
    return out


def analyse(shifted: pd.DataFrame, twin: pd.DataFrame | None,
            resamples: int = BOOTSTRAP_RESAMPLES) -> dict[str, Any]:
    """The joint fits of the shifted peg, the twin's single slope, the paired table."""
    shift = sorted(set(shifted["peg_com_shift_mm"].round(6)))
    doc: dict[str, Any] = {"com_shift_mm": shift, "max_fit_mm": MAX_FIT_MM, "fits": {}}
    for target, label in FIT_TARGETS:
        doc["fits"][label] = {"shifted_joint": fit(shifted, target, True, resamples).as_dict()}
        if twin is not None:
            doc["fits"][label]["twin"] = fit(twin, target, False, resamples).as_dict()
    if twin is not None:
        doc["paired"] = paired_by_offset(shifted, twin)
    doc["verdict"] = verdict(doc)
    return doc


def _ci_excludes_zero(entry: dict[str, Any]) -> int:
    """+1 above zero, -1 below, 0 where the interval spans zero or is undefined."""
    lo, hi = entry["ci95"]
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return 0
    return 1 if lo > 0 else -1 if hi < 0 else 0


def verdict(doc: dict[str, Any]) -> str:
    """One sentence per fitted time: which distance the times follow."""
    parts = []
    for label, fits in doc["fits"].items():
        joint = fits["shifted_joint"]
        m = _ci_excludes_zero(joint["per_mm_from_middle_s"])
        c = _ci_excludes_zero(joint["per_mm_from_com_s"])
        if c > 0 and m <= 0:
            said = "the distance from the centre of mass (the mass, eq. 2-3)"
        elif m > 0 and c <= 0:
            said = "the distance from the middle (the peg's geometry), not the centre of mass"
        elif m > 0 and c > 0:
            said = "both distances"
        else:
            said = "neither distance measurably"
        parts.append(f"{label}: {said}")
    return "; ".join(parts)


def markdown(doc: dict[str, Any]) -> str:
    """The fits and the paired table as Markdown."""
    lines = [f"Centre of mass {', '.join(f'{s:g}' for s in doc['com_shift_mm'])} mm from the "
             f"middle; fits over successful trials within +-{doc['max_fit_mm']:g} mm of the "
             "middle (95 % bootstrap intervals over scenes).", "",
             "| time | peg | n | intercept [s] | per mm from the middle [s] | per mm from the "
             "centre of mass [s] |", "|---|---|---|---|---|---|"]

    def cell(entry: dict[str, Any] | None) -> str:
        if entry is None:
            return "-"
        lo, hi = entry["ci95"]
        return f"{entry['value']:+.3f} [{lo:+.3f}, {hi:+.3f}]"

    for label, fits in doc["fits"].items():
        for peg, key in (("shifted", "shifted_joint"), ("uniform twin", "twin")):
            f = fits.get(key)
            if f is None:
                continue
            lines.append(f"| {label} | {peg} | {f['n']} | {cell(f['intercept_s'])} | "
                         f"{cell(f['per_mm_from_middle_s'])} | "
                         f"{cell(f.get('per_mm_from_com_s'))} |")
    if "paired" in doc:
        lines += ["", "| offset from the middle [mm] | assembled, shifted / twin | median "
                      "|offset from the centre of mass| [mm] | time, shifted - twin [s] |",
                  "|---|---|---|---|"]
        for r in doc["paired"]:
            lines.append(f"| {r['offset_mm']:+g} | {r['assembled']} / {r['assembled_twin']} "
                         f"of {r['trials']} | {r['median_grasp_offset_com_mm']:.1f} | "
                         f"{r['time_diff_mean_s']:+.2f} |")
    lines += ["", f"The times follow {doc['verdict']}."]
    return "\n".join(lines) + "\n"
