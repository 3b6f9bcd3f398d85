"""One column vocabulary with units (:mod:`vgs.columns`) across every table and journal, strict
JSON in every JSON file, and tables written before the vocabulary still loading."""

from __future__ import annotations

import csv
import json
import math
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from vgs.assembly.record import PHASES, EpisodeRecord
from vgs.columns import (
    COLUMNS,
    KINDS,
    LEGACY,
    SUMMARY_COLUMNS,
    UNIT_SUFFIXES,
    markdown,
)
from vgs.config import profile
from vgs.experiments import sweep
from vgs.experiments.evaluate import EvalSpec, plan_episodes
from vgs.jsonsafe import dumps
from vgs.runfolder import trainfolder
from vgs.runfolder.common import read_table
from vgs.runfolder.journal import encode_row, read_journal
from vgs.runfolder.status import flag_count

ROOT = Path(__file__).resolve().parents[1]
# statistics over episodes, not episode rows
SUMMARY_TABLES = ("results.csv", "seeds.csv", "field.csv")
ARROW_KINDS = {"bool": ("bool",), "int": ("int64", "int32"), "float": ("double", "float"),
               "str": ("string", "large_string")}


def strict_loads(text: str) -> Any:
    """``json.loads`` that refuses the bare ``NaN``, ``Infinity`` and ``-Infinity`` that
    Python's default writes and strict JSON readers reject."""
    def refuse(name: str) -> Any:
        raise ValueError(f"not strict JSON: bare {name}")

    return json.loads(text, parse_constant=refuse)


# -- the vocabulary itself -------------------------------------------------------------------


def test_names_carry_their_units_and_the_mapping_is_closed() -> None:
    for name, col in {**COLUMNS, **SUMMARY_COLUMNS}.items():
        assert col.kind in KINDS and col.description and "\n" not in col.description, name
        assert col.unit == "" or col.unit in UNIT_SUFFIXES, name
        if col.unit:
            assert col.kind == "float", name
    for name, col in COLUMNS.items():  # episode columns: the unit is the name's suffix
        suffixes = [s for s in UNIT_SUFFIXES.values() if name.endswith(s)]
        if col.unit:
            assert name.endswith(UNIT_SUFFIXES[col.unit]), name
        else:
            assert not suffixes, f"{name} looks like a quantity with a unit"
    for old, (new, factor) in LEGACY.items():
        assert old not in COLUMNS and new in COLUMNS and factor > 0
    # every column a row can hold is in the vocabulary
    assert set(EpisodeRecord(0, 0.55, 0.1).to_row()) <= set(COLUMNS)
    assert {f"time_{p}_s" for p in PHASES} <= set(COLUMNS)
    assert set(trainfolder.CSV_COLUMNS) <= set(COLUMNS) and set(sweep.COLUMNS) <= set(COLUMNS)


def test_record_row_converts_units() -> None:
    record = EpisodeRecord(seed=3, peg_mass=0.6, peg_length=0.11, grasp_success=True,
                           grasp_offset=-0.012, success=True, assembly_time=40.5,
                           peak_moment_measured=0.8, peak_grasp_moment=0.4)
    row = record.to_row()
    assert row["peg_mass_kg"] == 0.6 and row["peg_length_mm"] == pytest.approx(110.0)
    assert row["grasp_offset_mm"] == pytest.approx(-12.0) and row["assembly_time_s"] == 40.5
    assert row["assembly_success"] is True and row["grasp_success"] is True
    assert row["peak_moment_measured_nm"] == 0.8 and row["peak_grasp_moment_nm"] == 0.4
    assert not set(row) & set(LEGACY)


def test_docs_list_the_vocabulary() -> None:
    """docs/columns.md holds the table :func:`vgs.columns.markdown` gives."""
    text = (ROOT / "docs" / "columns.md").read_text()
    assert markdown() in text
    assert markdown(SUMMARY_COLUMNS) in text


def test_strict_json_and_the_journal_checksum() -> None:
    assert dumps({"a": math.nan, "b": [math.inf, -math.inf], "c": np.float32(1.5),
                  "d": np.int64(2), "e": (np.bool_(True),)}) == \
        '{"a": null, "b": [null, null], "c": 1.5, "d": 2, "e": [true]}'
    line = encode_row({"index": 0, "assembly_time_s": math.nan})
    row = strict_loads(line)
    crc = row.pop("crc32")
    assert row["assembly_time_s"] is None and crc == zlib.crc32(json.dumps(row).encode())


# -- what the runs write ---------------------------------------------------------------------


def _check_value(name: str, value: Any, where: str) -> None:
    col = COLUMNS[name]
    if col.kind == "bool":
        assert isinstance(value, bool), f"{where}: {name} = {value!r} is not a boolean"
    elif col.kind == "float":
        assert value is None or isinstance(value, int | float) and not isinstance(value, bool), \
            f"{where}: {name} = {value!r}"
    elif col.kind == "int":
        assert isinstance(value, int) and not isinstance(value, bool), f"{where}: {name}"
    else:
        assert isinstance(value, str), f"{where}: {name} = {value!r}"


@pytest.mark.slow
def test_every_table_and_json_file_a_reproduction_writes(quick_reproduction: Any,
                                                         tmp_path: Path) -> None:
    """The reduced ``vgs reproduce`` (training, evaluation, sweep, report), then ``vgs seeds``
    and ``vgs export-policy`` on it: every table and journal uses the vocabulary (units in the
    parquet metadata, booleans as booleans, no legacy name), one quantity has one name and one
    unit everywhere, and every JSON file parses as strict JSON."""
    from vgs.analysis.seeds import seeds_report
    from vgs.tools.export_policy import export_policy

    out = quick_reproduction.out
    assert quick_reproduction.proc.returncode == 0, quick_reproduction.proc.stderr
    seeds_report([out], tmp_path / "seeds")
    export_policy(out / "train" / "vgs_s0", tmp_path / "policy" / "policy.pt")
    roots = (out, tmp_path)

    def files(pattern: str) -> list[Path]:
        return sorted(p for root in roots for p in root.rglob(pattern))

    # tables: parquet
    parquets = files("*.parquet")
    assert len(parquets) == 12  # 6 evaluations, 6 merged tables
    seen: dict[str, dict[str, set[float]]] = {}
    for path in parquets:
        schema = pq.read_schema(path)
        for field in schema:
            assert field.name in COLUMNS, f"{path}: {field.name} is not in the vocabulary"
            col = COLUMNS[field.name]
            meta = {k.decode(): v.decode() for k, v in (field.metadata or {}).items()}
            assert meta == {"unit": col.unit, "description": col.description}, path
            assert str(field.type) in ARROW_KINDS[col.kind], (path, field.name, field.type)
        df = pd.read_parquet(path)
        for name in ("peg_mass_kg", "peg_length_mm", "grasp_offset_mm", "assembly_time_s"):
            seen.setdefault(name, {}).setdefault(str(path), set()).update(
                df[name].dropna().tolist())
    # tables: CSV (episode tables in the vocabulary, summary tables in theirs)
    csvs = files("*.csv")
    names = sorted({p.name for p in csvs})
    assert names == ["episodes.csv", "field.csv", "results.csv", "seeds.csv", "sweep.csv"], names
    for path in csvs:
        with path.open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        header = list(rows[0]) if rows else []
        vocabulary = SUMMARY_COLUMNS if path.name in SUMMARY_TABLES else COLUMNS
        assert header and set(header) <= set(vocabulary), (path, set(header) - set(vocabulary))
        assert not set(header) & set(LEGACY), path
        for name in header:
            if name in COLUMNS and COLUMNS[name].kind == "bool":
                assert {r[name] for r in rows} <= {"True", "False"}, (path, name)
        if path.name not in SUMMARY_TABLES:
            df = read_table(path)
            for name in ("peg_mass_kg", "peg_length_mm", "grasp_offset_mm", "assembly_time_s"):
                if name in df:
                    seen.setdefault(name, {}).setdefault(str(path), set()).update(
                        df[name].dropna().tolist())
    # journals: strict JSON, the vocabulary, JSON booleans
    journals = files("*.jsonl")
    assert len(journals) == 7  # 6 evaluations and the sweep
    for path in journals:
        lines = path.read_text().splitlines()
        assert lines
        for number, line in enumerate(lines, start=1):
            row = strict_loads(line)
            where = f"{path}:{number}"
            assert set(row) - {"crc32"} <= set(COLUMNS), (where, set(row) - set(COLUMNS))
            for name, value in row.items():
                if name != "crc32":
                    _check_value(name, value, where)
            for name in ("peg_mass_kg", "peg_length_mm", "grasp_offset_mm", "assembly_time_s"):
                if row.get(name) is not None:
                    seen.setdefault(name, {}).setdefault(str(path), set()).add(row[name])
    # one quantity, one unit: the peg is about 0.55 kg and 100 mm long in every table
    for name, (low, high) in {"peg_mass_kg": (0.3, 1.0), "peg_length_mm": (50.0, 200.0),
                              "grasp_offset_mm": (-100.0, 100.0),
                              "assembly_time_s": (0.0, 1000.0)}.items():
        values = [v for by_file in seen[name].values() for v in by_file]
        assert values and all(low <= v <= high for v in values), (name, seen[name])
    assert len(seen["peg_length_mm"]) >= 12 + 6 + 6 + 1  # parquet, csv, journals, sweep
    # JSON files, and the JSON inside the checkpoints: strict
    documents = files("*.json")
    names = sorted({p.name for p in documents})
    assert names == ["convergence.json", "meta.json", "policy.json", "reproduce.json",
                     "run.json", "summary.json", "sweep.json", "threshold.json"], names
    for path in documents:
        strict_loads(path.read_text())
    checkpoints = files("checkpoint.pt")
    assert len(checkpoints) == 2
    for path in checkpoints:
        with zipfile.ZipFile(path) as zf:
            strict_loads(zf.read("meta.json").decode())


# -- what was published before the vocabulary --------------------------------------------------


def test_legacy_tables_still_load(tmp_path: Path) -> None:
    """An evaluation table with the names before the vocabulary (``peg_mass``, ``peg_length``
    [m], ``grasp_offset`` [m], ``success``, ``assembly_time``) and a training table with
    booleans as 0/1 (and one resumed after the change, 0/1 then True/False) load in it."""
    path = ROOT / "tests" / "data" / "report_small" / "eval" / "vgs" / "mass" / "episodes.parquet"
    raw = pd.read_parquet(path)
    assert {"peg_mass", "peg_length", "grasp_offset", "success", "assembly_time"} <= set(raw)
    df = read_table(path)
    assert not set(df.columns) & set(LEGACY)
    assert set(df.columns) <= set(COLUMNS)
    assert np.allclose(df["peg_length_mm"], 1000.0 * raw["peg_length"])
    assert np.allclose(df["peg_mass_kg"], raw["peg_mass"])
    assert np.allclose(df["grasp_offset_mm"].dropna(), raw["grasp_offset_mm"].dropna())
    assert df["assembly_success"].dtype == bool
    assert (df["assembly_success"] == raw["success"]).all()
    assert np.array_equal(df["assembly_time_s"].to_numpy(float),
                          raw["assembly_time"].to_numpy(float), equal_nan=True)
    # a training table of 0/1 booleans, and one with both (a run resumed across the change)
    header = ",".join(trainfolder.CSV_COLUMNS)
    for flags in (("0", "1"), ("1", "True"), ("False", "0")):
        lines = [header]
        for i, flag in enumerate(flags):
            row = dict.fromkeys(trainfolder.CSV_COLUMNS, "0")
            row.update(episode=str(i), mode="vgs", grasp_success=flag, assembly_success=flag,
                       explored=flag, failure_reason="")
            lines.append(",".join(row[c] for c in trainfolder.CSV_COLUMNS))
        table = tmp_path / "episodes.csv"
        table.write_text("\n".join(lines) + "\n")
        df = read_table(table)
        for name in ("grasp_success", "assembly_success", "explored"):
            assert df[name].dtype == bool
            assert df[name].tolist() == [f in ("1", "True") for f in flags]
    assert [flag_count(v) for v in ("1", "0", "True", "False", "", "x")] == [1, 0, 1, 0, 0, 0]


def test_legacy_journal_still_reads(tmp_path: Path) -> None:
    """An evaluation journal written before the vocabulary (legacy names, bare NaN, the CRC of
    Python's default JSON) is read and checked against the plan; its rows come in the
    vocabulary."""
    cfg = profile("smoke")
    plan = plan_episodes(cfg, EvalSpec("center", "length", 2, seed=4))
    lines = []
    for task in plan:
        row = {"job": 0, "index": task.index, "seed": task.seed, "peg_mass": task.peg.mass,
               "peg_length": task.peg.length, "grasp_success": True, "grasp_offset": 0.002,
               "success": task.index == 0, "failure_reason": "" if task.index == 0 else "grasp",
               "assembly_time": 30.0 if task.index == 0 else math.nan,
               "peak_moment_measured": math.nan, "grasp_offset_mm": 2.0}
        body = json.dumps(row)  # the encoder before strict JSON: bare NaN
        lines.append(f"{body[:-1]}, \"crc32\": {zlib.crc32(body.encode())}}}\n")
    journal = tmp_path / "journal.jsonl"
    journal.write_text("".join(lines))
    assert "NaN" in journal.read_text()
    rows, cut = read_journal(journal, plan)
    assert not cut and sorted(rows) == [0, 1]
    assert rows[0]["assembly_success"] is True and rows[0]["assembly_time_s"] == 30.0
    assert math.isnan(rows[1]["assembly_time_s"]) and math.isnan(rows[1]["peak_moment_measured_nm"])
    assert rows[1]["peg_length_mm"] == pytest.approx(1000.0 * plan[1].peg.length)
    assert rows[0]["grasp_offset_mm"] == 2.0 and "grasp_offset" not in rows[0]
    assert not set(rows[0]) & set(LEGACY)
    # written again (a resume rewrites a journal whose last line was cut): strict, same rows
    again = tmp_path / "again.jsonl"
    again.write_text("".join(encode_row(rows[i]) for i in sorted(rows)))
    for line in again.read_text().splitlines():
        strict_loads(line)
    rows2, _ = read_journal(again, plan)
    assert json.dumps(rows2, sort_keys=True) == json.dumps(rows, sort_keys=True)


def test_an_evaluation_started_before_the_vocabulary_resumes(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A journal of legacy rows (old names and units, bare NaN, the old checksum) resumed by
    this vgs gives the table an uninterrupted run writes (physics-free stand-in)."""
    from experiments import fakes
    from vgs.experiments import evaluate as evaluate_mod
    from vgs.rollout import episodepool

    monkeypatch.setattr(episodepool, "EpisodeRunner", fakes.FakeRunner)
    cfg = fakes.tiny_config()
    spec = EvalSpec("random", "length", 4, seed=2)
    reference = evaluate_mod.evaluate(cfg, spec, tmp_path / "ref", workers=1, progress=False)
    rows, _ = read_journal(tmp_path / "ref" / "journal.jsonl")
    old = {new: legacy for legacy, (new, _) in LEGACY.items()
           if legacy not in ("mass_kg", "length_mm")}
    lines = []
    for i in (0, 1):  # the first two episodes, as the evaluation before the change wrote them
        row = {}
        for key, value in rows[i].items():
            if key == "grasp_offset_mm":
                row["grasp_offset"] = value / 1000.0
                row[key] = value
            elif key == "peg_length_mm":
                row["peg_length"] = value / 1000.0
            else:
                row[old.get(key, key)] = value
        body = json.dumps(row)
        lines.append(f"{body[:-1]}, \"crc32\": {zlib.crc32(body.encode())}}}\n")
    text = "".join(lines)
    assert "NaN" in text and '"peg_length": 0.' in text and '"success": ' in text
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "journal.jsonl").write_text(text)
    resumed = evaluate_mod.evaluate(cfg, spec, tmp_path / "old", workers=1, progress=False)
    assert list(resumed.columns) == list(reference.columns)
    pd.testing.assert_frame_equal(resumed.drop(columns="wall_s"),
                                  reference.drop(columns="wall_s"), rtol=1e-12)
    assert not set(pq.read_schema(tmp_path / "old" / "episodes.parquet").names) & set(LEGACY)
