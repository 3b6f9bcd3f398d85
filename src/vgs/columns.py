"""The column vocabulary of every table and journal vgs writes, with units.

One name means one quantity in one unit wherever it appears: the evaluation tables
(``episodes.parquet``, ``episodes.csv``) and their ``journal.jsonl``, training's
``episodes.csv``, the sweep's ``sweep.csv`` and its ``journal.jsonl``; an episode's per-tick
trace (:data:`TRACE_COLUMNS`, :mod:`vgs.tools.trace`). A name carries its unit as a suffix
(``_s``, ``_h``, ``_mm``, ``_kg``, ``_n`` for N, ``_nm`` for N m, ``_deg``, ``_pct``);
booleans are stored as booleans. :data:`COLUMNS` gives each name its unit, kind and a one-line
description; parquet files carry the unit and the description in each field's metadata
(:func:`write_parquet`). The summary tables built from them (the report's ``results.csv``,
``seeds.csv``) are listed in :data:`SUMMARY_COLUMNS`.

:data:`LEGACY` maps each name that tables used before (and that the attributes of
:class:`vgs.assembly.record.EpisodeRecord` still use, in SI units) to its name here, with the
factor that converts the value; readers apply it on load (:func:`normalize`,
:func:`normalize_row`), so results published before keep loading.

Torch-, pandas- and MuJoCo-free at import (``vgs status`` uses it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

UNIT_SUFFIXES: dict[str, str] = {"s": "_s", "h": "_h", "mm": "_mm", "kg": "_kg", "N": "_n",
                                 "N m": "_nm", "deg": "_deg", "%": "_pct"}
KINDS = ("bool", "int", "float", "str")


@dataclass(frozen=True)
class Column:
    """One column.

    Attributes:
        unit: Physical unit (a key of :data:`UNIT_SUFFIXES`), or ``""`` for counts, indices,
            labels, ratios and booleans.
        kind: ``bool``, ``int``, ``float`` or ``str``.
        description: One line.
    """

    unit: str
    kind: str
    description: str


PHASE_NAMES = ("transport", "approach", "search", "slide", "align", "insert")

COLUMNS: dict[str, Column] = {
    # which row
    "index": Column("", "int", "episode index within the evaluation's plan"),
    "job": Column("", "int", "which of the evaluations run together the row belongs to "
                             "(journal only)"),
    "policy": Column("", "str", "policy label: baseline, vgs, center, random, com-oracle or a "
                                "user policy"),
    "condition": Column("", "str", "test condition: nominal, mass, length, com, com-hidden or "
                                      "com-spread"),
    "root_seed": Column("", "int", "root seed of the evaluation"),
    "train_run": Column("", "str", "training seed the policy comes from, s<seed> (its run is "
                                   "train/<mode>_s<seed>; tables merged over training seeds)"),
    "episode": Column("", "int", "training episode number, from 0"),
    "mode": Column("", "str", "training mode: vgs or baseline"),
    "trial": Column("", "int", "sweep scene number: the same scene at every offset"),
    "seed": Column("", "int", "episode seed: peg pose, hole displacement, sensor noise"),
    # the peg and the scene
    "offset_mm": Column("mm", "float", "commanded grasp offset from the visible peg centre "
                                       "along its axis (sweep)"),
    "peg_mass_kg": Column("kg", "float", "peg mass"),
    "peg_length_mm": Column("mm", "float", "peg length"),
    "peg_com_shift_mm": Column("mm", "float", "ground truth: the peg's centre of mass from its "
                                              "middle along the axis, towards its heavy end "
                                              "(0: a uniform peg)"),
    "hole_offset_mm": Column("mm", "float", "ground truth: displacement of the hole from its "
                                            "nominal position"),
    # the episode's outcome (the episode record)
    "grasp_success": Column("", "bool", "the RG2 holds the peg after the lift"),
    "grasp_offset_mm": Column("mm", "float", "ground truth, analysis only: signed distance "
                                             "along the peg axis from the peg's middle to the "
                                             "grasp point (NaN when not grasped)"),
    "grasp_offset_com_mm": Column("mm", "float", "ground truth, analysis only: signed distance "
                                                 "along the peg axis from its centre of mass to "
                                                 "the grasp point (NaN when not grasped)"),
    "assembly_success": Column("", "bool", "the peg ended inserted to the insertion depth"),
    "failure_reason": Column("", "str", "empty on success, else what stopped the episode "
                                        "(grasp, timeout:<phase>, unstable, "
                                        "not_inserted, peg_lost, error:..., worker_lost; in "
                                        "training: cutoff:<phase>, stopped at the reward "
                                        "threshold, and no_assembly)"),
    "assembly_time_s": Column("s", "float", "simulated time from the end of the grasp to the "
                                            "end of the insertion (NaN without an assembly)"),
    **{f"time_{p}_s": Column("s", "float", f"simulated time spent in the {p} phase")
       for p in PHASE_NAMES},
    "adjustments": Column("", "int", "alignment adjustments (wiggle iterations)"),
    "retries": Column("", "int", "new searches after a wrong contact-state decision"),
    "final_tilt_deg": Column("deg", "float", "ground truth: tilt of the peg axis from vertical "
                                             "at the end"),
    "insertion_depth_mm": Column("mm", "float", "ground truth: depth of the peg's lower end "
                                                "below the hole entrance at the end"),
    "peak_moment_measured_nm": Column("N m", "float", "largest moment about the pinch axis "
                                                      "the F/T sensor measured in contact"),
    "peg_turn_deg": Column("deg", "float", "ground truth, analysis only: largest turn of the "
                                           "peg's axis in the pads between grasp and release"),
    "peak_grasp_moment_nm": Column("N m", "float", "ground truth, analysis only: largest "
                                                   "moment about the pinch axis the fingers "
                                                   "exerted on the peg during the assembly"),
    "jaw_misalignment_deg": Column("deg", "float", "ground truth, analysis only: angle between "
                                                   "the pads' long side and the peg's axis in "
                                                   "the table plane at the decision, 0-90"),
    "along_mm": Column("mm", "float", "ground truth, analysis only (vgs grasp-sites): the "
                                      "chosen pixel's distance along the peg's axis from its "
                                      "centre of mass, signed"),
    "across_mm": Column("mm", "float", "ground truth, analysis only: the commanded grasp "
                                       "point's distance from the peg's axis across it, in "
                                       "the table plane, when the policy decided (every "
                                       "record; vgs grasp-sites recomputes it for old tables)"),
    # the policy's decision
    "rotation": Column("", "int", "index of the grasp rotation (-1: no network decision)"),
    "row": Column("", "int", "heightmap row of the grasp pixel (-1: none)"),
    "col": Column("", "int", "heightmap column of the grasp pixel (-1: none)"),
    "q_value": Column("", "float", "Q value of the chosen pixel (NaN when not computed)"),
    "epsilon": Column("", "float", "exploration probability of the episode"),
    "explored": Column("", "bool", "the grasp was a random exploration pixel"),
    # learning
    "r_grasp": Column("", "float", "grasp reward r_G"),
    "r_assembly": Column("", "float", "assembly reward r_AM"),
    "reward": Column("", "float", "reward R = r_G + r_AM"),
    "threshold_s": Column("s", "float", "assembly-time threshold of r_AM (empty before one "
                                        "exists)"),
    "loss": Column("", "float", "TD loss of the update"),
    "delta_q": Column("", "float", "|Q - y| of the executed action before the update"),
    # where and how long
    "wall_s": Column("s", "float", "wall-clock time the episode took in its process"),
    "host_cpu": Column("", "str", "CPU model of the host that ran the episode"),
    "mujoco_version": Column("", "str", "MuJoCo version of that host"),
}

_RATE = "fraction of the episodes"
# The gains of VGS over the baseline (vgs.analysis.stats): on the mean times of the successes
# (the report, seeds.csv) and on the summed times of all attempts (seeds.csv).
_GAINS = (("gain", "efficiency gain over the baseline, (T_base - T) / T_base on the mean times "
                   "of the successes"),
          ("total_gain", "gain in total time over the baseline, (S_base - S) / S_base on the "
                         "summed times of all attempts (the paper's measure)"),
          ("success_total_gain", "gain in total time over the baseline with the failed "
                                 "attempts left out: the summed times of the successes"),
          ("align_gain", "gain on the mean alignment time of the successes (the phase the "
                         "paper studies)"))
_FIELD_STATS = (
    *((f"iqm_s_{p}", "s", f"interquartile mean of the successes' assembly times, {p}")
      for p in ("baseline", "vgs", "center")),
    *((f"p_faster_than_{p}", "", f"probability that VGS assembles faster than the {p} on a "
                                 "random paired scene of a random run")
      for p in ("baseline", "center")),
)
_INTERVAL_ENDS = (("", ""),
                  ("_ci_low", ": lower end of its crossed-bootstrap 95 % interval"),
                  ("_ci_high", ": upper end of its crossed-bootstrap 95 % interval"))

SUMMARY_COLUMNS: dict[str, Column] = {
    "condition": COLUMNS["condition"],
    "policy": COLUMNS["policy"],
    "train_run": Column("", "str", "training run, or mean over the training runs"),
    "source": Column("", "str", "results folder the run was read from"),
    "episodes": Column("", "int", "test episodes"),
    "successes": Column("", "int", "successful assemblies"),
    "grasp_success_rate": Column("", "float", f"{_RATE} with a held grasp"),
    "success_rate": Column("", "float", f"{_RATE} assembled"),
    "time_total_h": Column("h", "float", "total assembly time of the successes"),
    "time_all_h": Column("h", "float", "total assembly time of all attempts, failed ones until "
                                       "given up (the paper's total over its 1000 tests)"),
    **{f"time_{stat}_s": Column("s", "float", f"{stat} assembly time of the successes")
       for stat in ("mean", "std", "min", "max", "median")},
    "time_per_assembled_s": Column("s", "float", "assembly time of all attempts, failed ones "
                                                 "included, per assembled peg"),
    "abs_grasp_offset_mean_mm": Column("mm", "float", "mean distance of the grasp from the "
                                                      "peg's middle (its centre of mass on a "
                                                      "uniform peg)"),
    **{name: col for prefix, what in _GAINS for name, col in (
        (f"{prefix}_pct", Column("%", "float", what)),
        (f"{prefix}_ci_low", Column("%", "float", f"lower end of the 95 % interval of "
                                                  f"{prefix}_pct")),
        (f"{prefix}_ci_high", Column("%", "float", f"upper end of the 95 % interval of "
                                                   f"{prefix}_pct")),
        (f"{prefix}_t_low", Column("%", "float", f"lower end of Student's t 95 % interval of "
                                                 f"the mean {prefix}_pct over training runs")),
        (f"{prefix}_t_high", Column("%", "float", f"upper end of Student's t 95 % interval of "
                                                  f"the mean {prefix}_pct over training runs")),
        (f"{prefix}_sd_between_seeds", Column("%", "float", f"standard deviation of {prefix}_pct "
                                                            "between training runs")),
        (f"seeds_with_positive_{prefix}", Column("", "int", f"training runs whose {prefix}_pct "
                                                            "is positive")))},
    "seeds": Column("", "int", "training runs averaged"),
    # vgs seeds' field.csv: the statistics for few runs (Agarwal et al. 2021)
    "runs": Column("", "int", "training runs"),
    "scenes": Column("", "int", "test scenes shared by the runs"),
    **{f"{stat}{end}": Column(unit, "float", what + note)
       for stat, unit, what in _FIELD_STATS for end, note in _INTERVAL_ENDS},
    **{f"{name}_{policy}": Column(col.unit, col.kind, f"{col.description}, {policy}")
       for policy in ("baseline", "vgs")
       for name, col in (
           ("successes", Column("", "int", "successful assemblies")),
           ("grasp_success", Column("", "float", f"{_RATE} with a held grasp")),
           ("offset_mm", Column("mm", "float", "mean distance of the grasp from the peg's "
                                                "middle")),
           ("time_mean_s", Column("s", "float", "mean assembly time of the successes")),
           ("time_std_s", Column("s", "float", "standard deviation of the successes' assembly "
                                               "times")),
           ("time_all_h", Column("h", "float", "total assembly time of all attempts, failed "
                                               "ones until given up")),
           ("time_per_assembled_s", Column("s", "float", "assembly time per assembled peg, "
                                                         "failed attempts included")))},
}

# The UR5's joints in the order of the arm's qpos (vgs.sim.ur5.JOINT_NAMES, held by a test).
ARM_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
_GT = "ground truth, analysis only: "
# An episode's per-tick trace (vgs demo --trace, vgs evaluate --traces): one row per control
# tick, world frame (x, y on the table, z up from its top).
TRACE_COLUMNS: dict[str, Column] = {
    "time_s": Column("s", "float", "simulated time at the end of the control tick"),
    "phase": Column("", "str", "the robot's phase during the tick: idle, grasp, the assembly's "
                               "phases (time_<phase>_s sums their ticks), release"),
    **{f"tcp_{a}_mm": Column("mm", "float", f"TCP position, world {a}") for a in "xyz"},
    **{f"tcp_q{a}": Column("", "float", f"TCP orientation in the world, unit quaternion "
                                        f"(w, x, y, z; w >= 0): {a}") for a in "wxyz"},
    **{f"force_{a}_n": Column("N", "float", f"tared F/T force at the TCP, world {a} (what the "
                                            "controller reads)") for a in "xyz"},
    **{f"torque_{a}_nm": Column("N m", "float", f"tared F/T moment at the TCP, world {a}")
       for a in "xyz"},
    **{f"joint_{j}_deg": Column("deg", "float", f"UR5 {j} joint position") for j in ARM_JOINTS},
    "finger_width_mm": Column("mm", "float", "RG2 finger width: the two fingers' openings "
                                             "summed"),
    **{f"peg_tip_{a}_mm": Column("mm", "float", f"{_GT}the peg's lower end, world {a}")
       for a in "xyz"},
    "peg_tilt_deg": Column("deg", "float", f"{_GT}the peg axis's angle from vertical, 0-90"),
    **{f"hole_{a}_mm": Column("mm", "float", f"{_GT}the hole's true centre, world {a} "
                                             "(the same every tick)") for a in "xy"},
}

# Legacy name -> (name, factor that converts the value). The attributes of the episode record
# keep the legacy names (SI units), so EpisodeRecord.to_row() goes through this mapping too.
LEGACY: dict[str, tuple[str, float]] = {
    "peg_mass": ("peg_mass_kg", 1.0),  # evaluation tables and journals before 2026-12
    "mass_kg": ("peg_mass_kg", 1.0),  # sweep
    "peg_length": ("peg_length_mm", 1000.0),  # [m]
    "length_mm": ("peg_length_mm", 1.0),  # sweep
    "grasp_offset": ("grasp_offset_mm", 1000.0),  # [m]
    "grasp_offset_com": ("grasp_offset_com_mm", 1000.0),  # [m]
    "success": ("assembly_success", 1.0),
    "assembly_time": ("assembly_time_s", 1.0),
    "peak_moment_measured": ("peak_moment_measured_nm", 1.0),
    "peak_grasp_moment": ("peak_grasp_moment_nm", 1.0),
}


def column(name: str) -> Column:
    """The column ``name`` (:data:`COLUMNS`, then :data:`SUMMARY_COLUMNS`, then
    :data:`TRACE_COLUMNS`).

    Raises:
        KeyError: If vgs writes no such column.
    """
    found = COLUMNS.get(name) or SUMMARY_COLUMNS.get(name) or TRACE_COLUMNS.get(name)
    if found is None:
        raise KeyError(f"{name!r} is not a column of vgs's tables")
    return found


def as_bool(value: Any) -> bool | None:
    """A boolean cell as written by any vgs version (True/False, 1/0, their strings), or None
    when it is none of them (empty, NaN)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float) and value in (0, 1):
        return bool(value)
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        return as_bool(value.item())
    if isinstance(value, str):
        return {"true": True, "false": False, "1": True, "0": False, "1.0": True,
                "0.0": False}.get(value.strip().lower())
    return None


def normalize_row(row: dict[str, Any]) -> dict[str, Any]:
    """A row (a journal line, a record's fields) in this vocabulary: legacy names renamed and
    converted (:data:`LEGACY`; a legacy name whose new name is already there is dropped), JSON
    ``null`` in float columns back to NaN, booleans as booleans. Keys keep their order."""
    out: dict[str, Any] = {}
    for key, value in row.items():
        if key in LEGACY:
            new, factor = LEGACY[key]
            if new in row:
                continue
            if factor != 1.0 and isinstance(value, int | float) and not isinstance(value, bool):
                value = value * factor
            key = new
        out[key] = value
    for key, value in out.items():
        col = COLUMNS.get(key)
        if col is None:
            continue
        if col.kind == "float" and value is None:
            out[key] = math.nan
        elif col.kind == "bool" and not isinstance(value, bool):
            flag = as_bool(value)
            if flag is not None:
                out[key] = flag
    return out


def normalize(df: Any) -> Any:
    """A table (pandas DataFrame) in this vocabulary: legacy columns renamed and converted
    (:data:`LEGACY`; one whose new name is already there is dropped), boolean columns written
    as 0/1 or as strings made booleans. Returns a new frame; the column order is kept."""
    df = df.copy()
    drop = [old for old, (new, _) in LEGACY.items() if old in df.columns and new in df.columns]
    df = df.drop(columns=drop)
    for old, (_, factor) in LEGACY.items():
        if old in df.columns and factor != 1.0:
            df[old] = df[old] * factor
    df = df.rename(columns={old: new for old, (new, _) in LEGACY.items() if old in df.columns})
    for name in df.columns:
        col = COLUMNS.get(name)
        if col is None or col.kind != "bool" or str(df[name].dtype) == "bool":
            continue
        flags = [as_bool(v) for v in df[name]]
        if all(f is not None for f in flags):
            df[name] = flags
            df[name] = df[name].astype(bool)
    return df


def field_metadata(name: str) -> dict[str, str]:
    """``{"unit": ..., "description": ...}`` of a column (empty for one vgs does not know)."""
    try:
        col = column(name)
    except KeyError:
        return {}
    return {"unit": col.unit, "description": col.description}


# Decimals a table keeps per unit: the simulator resolves time to its 2 ms step (a control
# tick is 10 ms), so times are written to the ms (not 43.16000000001258); hours to 0.4 ms.
DECIMALS = {"s": 3, "h": 7}


def _decimals(name: str) -> int | None:
    found = COLUMNS.get(name) or SUMMARY_COLUMNS.get(name) or TRACE_COLUMNS.get(name)
    return DECIMALS.get(found.unit) if found is not None and found.kind == "float" else None


def rounded(df: Any) -> Any:
    """A copy of a table (pandas DataFrame) with its time columns rounded to :data:`DECIMALS`,
    for writing: records and journals keep full precision, so resuming compares them as
    computed."""
    df = df.copy()
    for name in df.columns:
        places = _decimals(str(name))
        if places is not None and df[name].dtype.kind == "f":
            df[name] = df[name].round(places)
    return df


def rounded_rows(rows: Any) -> list[dict[str, Any]]:
    """:func:`rounded` for rows (dicts), for ``csv.DictWriter``."""
    out = []
    for row in rows:
        row = dict(row)
        for name, value in row.items():
            places = _decimals(name)
            if places is not None and isinstance(value, float) and math.isfinite(value):
                row[name] = round(value, places)
        out.append(row)
    return out


def write_parquet(df: Any, path: Path, metadata: dict[str, str] | None = None) -> None:
    """Write a table (pandas DataFrame, no index) to ``path`` as parquet, each field's metadata
    holding its ``unit`` and ``description``; ``metadata`` (e.g.
    :func:`vgs.runfolder.common.provenance`) goes into the schema's metadata, read back with
    ``pyarrow.parquet.read_schema(path).metadata``."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(df, preserve_index=False)
    fields = [f.with_metadata(field_metadata(f.name)) if field_metadata(f.name) else f
              for f in table.schema]
    extra = {str(k).encode(): str(v).encode() for k, v in (metadata or {}).items()}
    schema = pa.schema(fields, metadata={**(table.schema.metadata or {}), **extra})
    pq.write_table(pa.Table.from_arrays(table.columns, schema=schema), path)


_FOLDED_SUFFIXES = ("_ci_low", "_ci_high", "_t_low", "_t_high", "_sd_between_seeds")


def markdown(names: Any = None) -> str:
    """The vocabulary (or the columns ``names``) as a Markdown table: name, unit, kind,
    description."""
    names = list(COLUMNS) if names is None else list(names)
    # An interval's ends and the like go on their quantity's row: `gain_pct` and
    # `gain_ci_low`, `gain_ci_high`, ... (the suffixes after the quantity's stem).
    folded: dict[str, list[str]] = {}
    hidden: set[str] = set()
    for name in names:
        for suffix in _FOLDED_SUFFIXES:
            if not name.endswith(suffix):
                continue
            stem = name[: -len(suffix)]
            base = next((b for b in (stem, f"{stem}_pct") if b in names), None)
            if base is not None:
                folded.setdefault(base, []).append(suffix)
                hidden.add(name)
                break
    lines = ["| column | unit | kind | description |", "|---|---|---|---|"]
    for name in names:
        if name in hidden:
            continue
        col = column(name)
        ends = "".join(f", `{e}`" for e in folded.get(name, []))
        lines.append(f"| `{name}`{ends} | {col.unit or '-'} | {col.kind} | {col.description} |")
    return "\n".join(lines) + "\n"
