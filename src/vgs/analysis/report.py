"""The reproduction report: our measurements beside the paper's (section 4.2, Figures 7-10).

``build_report(DIR)`` reads what ``vgs reproduce`` (or separate ``vgs train``/``evaluate``/
``sweep`` runs placed in the same layout) left in ``DIR``:

* ``eval/<policy>/<condition>/episodes.parquet``: one row per test episode;
* ``train/<mode>_s<seed>/``: training runs (learning curves, Q heat maps; optional);
* ``sweep/sweep.csv`` and ``sweep/sweep.png``: the grasp-position sweep (optional);
* ``reproduce.json``: profile, machine and stage wall times (optional);

and writes ``report.md``, a self-contained ``report.html`` (figures inlined), ``results.csv``
(the numbers of the tables) and the figures under ``figures/``.

Statistics. Times are simulated seconds of successful assemblies (grasp end to insertion end);
failed episodes count in the success rate only. The efficiency gain is
``(T_base - T_vgs) / T_base`` with ``T`` the mean assembly time (equal to the paper's ratio of
total times when both policies complete the same number of assemblies). Its 95 % confidence
interval comes from a paired bootstrap over test episodes (both policies meet the same scenes,
see :mod:`vgs.experiments.evaluate`): 2000 resamples of the episode indices, percentile interval.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import pandas as pd  # noqa: E402

from vgs.analysis.reportdoc import Doc  # noqa: E402
from vgs.analysis.reportfigures import (  # noqa: E402
    CONDITION_TITLES,
    plot_grasp_positions,
    plot_times,
    policy_order,
)
from vgs.analysis.stats import (  # noqa: E402
    ALIGN_GAIN,
    GAINS,
    MEAN_GAIN,
    MIN_SUCCESSES,
    SUCCESS_TOTAL_GAIN,
    TOTAL_GAIN,
    Gain,
    com_shifted,
    efficiency_gain,
    summarize,
)
from vgs.checkpoint import atomic_write_text  # noqa: E402
from vgs.columns import rounded  # noqa: E402
from vgs.config import CONDITIONS  # noqa: E402
from vgs.errors import ConfigError  # noqa: E402
from vgs.runfolder.common import (  # noqa: E402
    check_table_written,
    duration_text,
    read_json,
    read_table,
    short_revision,
)
from vgs.runfolder.layout import eval_tables, holds_network, train_folders  # noqa: E402


def load_paper_reference() -> dict[str, dict[str, Any]]:
    """The paper's reported values (section 4.2), for the report's comparison columns only.

    Read from ``paper_reference.json`` beside this module: ``[baseline, VGS]`` pairs and the
    gain in percent. The nominal means are derived from the totals (h x 3600 / 1000).
    """
    raw = json.loads((Path(__file__).with_name("paper_reference.json")).read_text())
    ref: dict[str, dict[str, Any]] = {}
    for condition, values in raw.items():
        if condition.startswith("_"):
            continue
        ref[condition] = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
        if "time_total_h" in ref[condition]:
            n = ref[condition]["episodes"]
            ref[condition]["time_mean_s"] = tuple(
                h * 3600.0 / e for h, e in zip(ref[condition]["time_total_h"], n, strict=True))
    return ref


PAPER = load_paper_reference()


# -- loading -------------------------------------------------------------------------------------


def load_results(out: Path) -> pd.DataFrame:
    """All evaluation tables under ``out/eval`` in one frame, in the column vocabulary of
    :mod:`vgs.columns` (tables published with the legacy names are renamed on load).

    Raises:
        ConfigError: If there are none.
    """
    tables = eval_tables(out)
    if not tables:
        raise ConfigError("report", f"no evaluation results under {out / 'eval'} "
                                    "(expected eval/<policy>/<condition>/episodes.parquet)")
    for t in tables:
        check_table_written(t)  # the table its evaluation wrote, not a changed one
    return pd.concat([read_table(t, "eval") for t in tables], ignore_index=True)


def load_center(folder: Path, tests: pd.DataFrame) -> pd.DataFrame:
    """The centre heuristic's tests in results folder ``folder``, on the scenes of ``tests``
    (:func:`vgs.analysis.makeup.check_center`).

    Raises:
        ConfigError: If ``folder`` holds no results, no centre evaluation or other scenes.
    """
    from vgs.analysis.makeup import check_center

    try:
        center = load_results(folder)
    except ConfigError as exc:
        raise ConfigError("center", exc.message) from exc
    return check_center(center, tests, folder)


def eval_wall_h(df: pd.DataFrame) -> dict[str, float]:
    """Each policy's summed test-episode wall time [h] (the ``wall_s`` column); empty for
    tables written before it was recorded."""
    if "wall_s" not in df.columns or not df["wall_s"].notna().any():
        return {}
    sums = df.groupby("policy", sort=True)["wall_s"].sum()
    return {str(k): float(v) / 3600.0 for k, v in sums.items()}


def hosts_note(df: pd.DataFrame) -> str:
    """A sentence on the hosts the test episodes ran on (``host_cpu``, ``mujoco_version``
    columns; tables written before they were recorded have none): empty when not recorded,
    a warning naming the evaluations whose episodes come from several hosts."""
    if "host_cpu" not in df.columns:
        return ""
    from vgs.runfolder.common import engine_note, hosts_of

    records = df[["host_cpu", "mujoco_version"]].to_dict("records")
    engine = engine_note(records)
    engine = f" **Engine.** The test episodes were {engine}." if engine else ""
    keys = [k for k in ("policy", "condition", "train_run") if k in df.columns]
    mixed = []
    for key, part in df.groupby(keys, sort=True):
        names = hosts_of(part[["host_cpu", "mujoco_version"]].to_dict("records"))
        if len(names) > 1:
            label = "/".join(str(k) for k in (key if isinstance(key, tuple) else (key,)))
            mixed.append(f"{label} ({'; '.join(names)})")
    if mixed:
        return ("**Hosts.** The episodes of " + ", ".join(mixed) + " come from several hosts: "
                "MuJoCo's floating point differs between CPUs, so the same scene can end "
                "differently on another host; compare such results with care." + engine)
    names = hosts_of(records)
    return (f"All test episodes ran on one host: {names[0]}." if names else "") + engine




def results_table(df: pd.DataFrame) -> pd.DataFrame:
    """One row per (condition, policy) with :func:`summarize` and the gain over the baseline."""
    rows = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        part = df[df["condition"] == condition]
        policies = policy_order(sorted(set(part["policy"])))
        base = part[part["policy"] == "baseline"]
        for policy in policies:
            mine = part[part["policy"] == policy]
            s = summarize(mine)
            s.pop("failure_reasons")
            row = {"condition": condition, "policy": policy, **s}
            for m in GAINS:
                gain = (efficiency_gain(base, mine, measure=m)
                        if policy != "baseline" and len(base)
                        else Gain(math.nan, math.nan, math.nan, False, 0))
                row.update({f"{m.name}_pct": gain.value, f"{m.name}_ci_low": gain.low,
                            f"{m.name}_ci_high": gain.high})
            rows.append(row)
    return pd.DataFrame(rows)






def _f(value: Any, digits: int = 1, suffix: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return f"{value:.{digits}f}{suffix}"


def _paper(condition: str, key: str, which: int, digits: int = 2) -> str:
    entry = PAPER.get(condition, {}).get(key)
    if entry is None:
        return "-"
    value = entry[which] if isinstance(entry, tuple) else entry
    return _f(float(value), digits)


def _paper_gain(condition: str) -> float | None:
    """The paper's gain in total time for a condition it tested; None for ours alone (`com`)."""
    gain = PAPER.get(condition, {}).get("gain")
    return None if gain is None else float(gain)


def _paper_gain_text(condition: str, suffix: str = "") -> str:
    paper = _paper_gain(condition)
    return "-" if paper is None else f"{paper:+.2f}{suffix}"


def _verdict(condition: str, gain: Gain, base: dict[str, Any], vgs: dict[str, Any],
             total: Gain | None = None) -> str:
    success = (f"success {base['success_rate']:.1%} (baseline, {base['successes']} of "
               f"{base['episodes']}) vs {vgs['success_rate']:.1%} (VGS, {vgs['successes']} of "
               f"{vgs['episodes']})")
    if not math.isfinite(gain.low):
        return (f"**{condition}**: too few successful assemblies to compare times (at least "
                f"{MIN_SUCCESSES} per policy needed); {success}.")
    paper = _paper_gain(condition)
    if gain.low > 0:
        verdict = "VGS was faster than the baseline (the 95 % interval excludes 0)"
    elif gain.high < 0:
        verdict = "VGS was SLOWER than the baseline (the 95 % interval excludes 0)"
    else:
        verdict = "no significant difference between VGS and the baseline (the 95 % interval " \
                  "includes 0)"
    if paper is None:
        like = (f"; in total time of all tests {total.text()} (a condition the paper did not "
                "test)" if total is not None else "")
    else:
        like = (f"; in total time of all tests {total.text()}, the measure of the paper's "
                f"{paper:+.2f} % (its total time over 1000 tests, none reported failed)"
                if total is not None else f" (paper, in total time: {paper:+.2f} %)")
    return (f"**{condition}**: {verdict}: gain on the mean time of successes {gain.text()}"
            f"{like}; {success}; std {_f(base['time_std_s'], 2)} vs "
            f"{_f(vgs['time_std_s'], 2)} s.")


ONE_STEP_TARGET = (
    "Each grasp is a terminal one-step episode (the next peg is placed independently of it), "
    "so the training target is y = R: gamma and the target network never affect learning, "
    "Delta Q = |R - Q_eva| of the grasp's own update, and a run counts as delta-Q converged "
    "when that Delta Q stayed below `agent.delta_q_threshold` in each of its last "
    "`agent.delta_q_window` episodes (the window's maximum, not its mean).")


def _timeouts_text(meta: dict[str, Any]) -> str:
    """`` (phase time-outs: search 60 s, ...)`` from a reproduction's recorded configuration,
    or ``""`` when it records none."""
    timeouts = meta.get("config", {}).get("assembly", {}).get("timeouts")
    if not timeouts:
        return ""
    pairs = timeouts.items() if isinstance(timeouts, dict) else timeouts
    return " (phase time-outs: " + ", ".join(f"{k} {float(v):g} s" for k, v in pairs) + ")"


def _training_rows(out: Path) -> list[list[str]]:
    rows = []
    for run in train_folders(out):
        csv_path = run / "episodes.csv"
        if not csv_path.exists():
            continue
        ep = read_table(csv_path, "train")
        last = ep.tail(max(1, len(ep) // 5))
        threshold = read_json(run / "threshold.json").get("threshold_s") \
            if (run / "threshold.json").exists() else None
        conv = read_json(run / "convergence.json") \
            if (run / "convergence.json").exists() else {}
        rows.append([run.name, str(len(ep)), _f(ep["grasp_success"].mean(), 2),
                     _f(last["assembly_success"].mean(), 2),
                     _f(last["grasp_offset_mm"].abs().mean()),
                     _f(threshold), str(conv.get("converged", "-"))])
    return rows


def provenance_text(made: Any) -> str:
    """``vgs 0.1.0 (source 1a2b3c4d5e), MuJoCo 4.0.0, torch 2.13.0`` of a recorded
    :func:`vgs.runfolder.common.provenance`; ``""`` for folders written before it was recorded."""
    if not isinstance(made, dict):
        return ""
    source = short_revision(made.get("source_revision"))
    return (f"vgs {made.get('vgs_version', '?')} (source {source}), MuJoCo "
            f"{made.get('mujoco_version', '?')}, torch {made.get('torch_version', '?')}")


def build_report(out: Path, title: str | None = None, center: Path | None = None) -> Path:
    """Write ``report.md``, ``report.html``, ``results.csv`` and figures into ``out``; the
    title defaults to the one ``vgs reproduce`` gives (the profile from ``reproduce.json``),
    so a re-run of ``vgs report`` keeps it.

    The sections in order: how the run was made (:func:`_provenance_section`), what its times
    are (:func:`_reading_section`), the headline and the verdicts (:func:`_headline_section`),
    what the gain is made of and VGS's regret against the centre heuristic (from ``out``'s own
    centre evaluation, or ``center``, a results folder with one on the same test scenes:
    :mod:`vgs.analysis.makeup`), each learned policy against the reference policies ``out``
    evaluated (``center``, ``com-oracle``), one section per condition
    (:func:`_condition_section`), where the policies grasp, the training runs
    (:func:`_training_section`) and the grasp-position sweep (:func:`_sweep_section`).

    Raises:
        ConfigError: If ``out`` holds no evaluation results, or ``center`` no centre evaluation
            of the same test scenes.
    """
    meta = read_json(out / "reproduce.json") if (out / "reproduce.json").exists() else {}
    df = load_results(out)
    _check_inputs(out)  # every file read below, before anything is written
    from vgs.analysis.makeup import makeups, write_makeup, write_references, write_regret

    centre = load_center(center, df) if center is not None else None
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    table = results_table(df)
    rounded(table).to_csv(out / "results.csv", index=False)  # times to the ms

    if title is None:
        title = "VGS reproduction report" + (f" ({meta['profile']} profile)"
                                             if meta.get("profile") else "")
    doc = Doc(out)
    doc.h(1, title)
    if gaps := missing_evaluations(out, meta, df):
        doc.p("**Not in this report, or only in part**: " + "; ".join(gaps) + ".")
    _provenance_section(doc, out, df, meta)
    _reading_section(doc, df)
    _headline_section(doc, df, table, meta)
    command = f"vgs report {out}" + (f" --center {center}" if center is not None else "")
    parts = makeups(df, centre)
    write_makeup(doc, parts, command)
    write_regret(doc, parts, command)
    write_references(doc, df, command)
    for condition in [c for c in CONDITIONS if c in set(table["condition"])]:
        _condition_section(doc, df, table, condition, figures)
    if PAPER["nominal"]:
        doc.p("Paper means are derived from its totals (h x 3600 / 1000).")

    doc.h(2, "Where the policies grasp")
    doc.img(plot_grasp_positions(df, figures / "grasp_positions.png"),
            "Realised grasp offset along the peg axis from its middle (and, where the centre "
            "of mass is off the middle, from the centre of mass), test episodes")

    _training_section(doc, out, figures)
    _sweep_section(doc, out)
    atomic_write_text(out / "report.md", doc.markdown())
    atomic_write_text(out / "report.html", doc.html(title))
    return out / "report.md"


def missing_evaluations(out: Path, meta: dict[str, Any], df: pd.DataFrame) -> list[str]:
    """What the reproduction in ``out`` planned (its ``reproduce.json``, ``meta``) that its
    merged tables ``df`` lack: a policy on a condition without a table, with fewer rows than
    planned, or without the ``summary.json`` that marks it finished. Empty without a
    ``reproduce.json`` (a folder of tables is read as it is)."""
    if not meta:
        return []
    from vgs.runfolder.layout import eval_jobs
    from vgs.runfolder.status import recorded_config

    cfg = recorded_config(out / "reproduce.json", meta["config"])
    planned: dict[tuple[str, str], int] = {}
    for job in eval_jobs(cfg, out):
        key = (job.label, job.condition)
        planned[key] = planned.get(key, 0) + cfg.eval.episodes
    counts = df.groupby(["policy", "condition"]).size().to_dict() if len(df) else {}
    gaps = []
    for (label, condition), n in planned.items():
        got = int(counts.get((label, condition), 0))
        where = f"eval/{label}/{condition}"
        if not got:
            gaps.append(f"{label} on {condition} (no table in {where})")
        elif got < n:
            gaps.append(f"{label} on {condition} ({got} of {n} test episodes in {where})")
        elif not (out / where / "summary.json").exists():
            gaps.append(f"{label} on {condition} (unfinished: {where} has no summary.json)")
    return gaps


def _check_inputs(out: Path) -> None:
    """Read (and so check against their schemas) the training runs' ``run.json`` and
    ``episodes.csv`` and the evaluations' ``meta.json`` that the report uses.

    Raises:
        CorruptFileError: Naming the first damaged file.
    """
    for run in sorted((out / "train").glob("*")):
        if (run / "run.json").exists():
            read_json(run / "run.json")
        if (run / "episodes.csv").exists():
            read_table(run / "episodes.csv", "train")
    for meta in sorted((out / "eval").glob("**/meta.json")):
        read_json(meta)


def _provenance_section(doc: Doc, out: Path, df: pd.DataFrame, meta: dict[str, Any]) -> None:
    """How the run was made: command, machine, revision, engine, wall times, shortcuts."""
    tested = [provenance_text(read_json(m).get("provenance"))
              for m in sorted((out / "eval").glob("**/meta.json"))]
    tested_text = "Test episodes made with " + "; ".join(dict.fromkeys(t for t in tested if t))
    if any(tested) and not meta:
        doc.p(tested_text + ".")
    if meta:
        doc.p(f"Profile `{meta.get('profile')}`, command `{meta.get('command')}`, on "
              f"{meta.get('machine', '?')}; source {short_revision(meta.get('git_revision'))}; "
              f"finished {meta.get('finished', '?')}.")
        made = provenance_text(meta.get("provenance"))
        if made:
            doc.p(f"Made with {made}.")
        if any(tested):
            doc.p(tested_text + ".")
        stages = meta.get("stage_wall_s", {})
        if stages:
            doc.p("Wall time per stage: " + ", ".join(
                f"{k} {duration_text(v)}" for k, v in stages.items())
                + f" ({duration_text(sum(stages.values()))} in all).")
        own = {run.name: read_table(run / "episodes.csv", "train")["wall_s"].sum() / 3600.0
               for run in train_folders(out) if (run / "episodes.csv").exists()}
        if own:
            doc.p("Each training run's own wall time, the sum of its table's `wall_s` (it "
                  "counts a run trained outside `vgs reproduce`, interrupted or moved between "
                  "machines; runs trained side by side overlap): " + ", ".join(
                      f"{name} {duration_text(3600 * h)}" for name, h in own.items()) + ".")
        tests = eval_wall_h(df)
        if tests:
            doc.p("The test episodes' own wall time, the sum of their `wall_s` per policy (it "
                  "counts evaluations interrupted or moved between machines, which the stage "
                  "times above miss; episodes run side by side overlap, so the elapsed time is "
                  "about this sum over the number of workers): " + ", ".join(
                      f"{name} {duration_text(3600 * h)}" for name, h in tests.items())
                  + f" ({duration_text(3600 * sum(tests.values()))} in all).")
        train_cfg = meta.get("config", {}).get("train", {})
        shortcuts = []
        if train_cfg.get("assemble_baseline") is False:
            shortcuts.append("the baseline's training grasps ran without the assembly (its "
                             "reward is the grasp's)")
        if train_cfg.get("stop_at_threshold"):
            shortcuts.append("VGS's training assemblies stopped at the frozen reward threshold")
        if shortcuts:
            doc.p("Training shortcuts (the same rewards, updates and networks as whole "
                  "episodes; docs/training.md): " + "; ".join(shortcuts) + ". The training "
                  "tables' assembly times are absent or censored there; the tests run whole.")


def _reading_section(doc: Doc, df: pd.DataFrame) -> None:
    """What the times are, and the hosts that made them."""
    doc.p("All times are **simulated** seconds of successful assemblies in our MuJoCo cell "
          "(UR5 + RG2, F/T-driven compliance). The paper's absolute times come from its own "
          "simulator and controller; compare the gains, spreads and the direction of effects, "
          "not the absolute seconds. Failed episodes count in the success rate only. Gain = "
          "(T_base - T_VGS) / T_base on mean times, 95 % paired-bootstrap interval.")

    host_note = hosts_note(df)
    if host_note:
        doc.p(host_note)


def _headline_section(doc: Doc, df: pd.DataFrame, table: pd.DataFrame,
                      meta: dict[str, Any]) -> None:
    """The gains of VGS per condition in one table, then a sentence per condition."""
    head_rows = []
    for condition in [c for c in CONDITIONS if c in set(table["condition"])]:
        part = table[table["condition"] == condition].set_index("policy")
        if not {"baseline", "vgs"} <= set(part.index):
            continue
        g, b = part.loc["vgs"], part.loc["baseline"]

        def gain(m: Any, g: pd.Series = g) -> str:
            return Gain(g[f"{m.name}_pct"], g[f"{m.name}_ci_low"], g[f"{m.name}_ci_high"],
                        True, 0).text()

        head_rows.append([condition, str(int(b["episodes"])),
                          f"{b['success_rate']:.1%} / {g['success_rate']:.1%}",
                          f"{_f(b['time_std_s'], 2)} / {_f(g['time_std_s'], 2)}",
                          gain(TOTAL_GAIN), _paper_gain_text(condition, " %"),
                          gain(SUCCESS_TOTAL_GAIN), gain(MEAN_GAIN), gain(ALIGN_GAIN)])
    if head_rows:
        doc.h(2, "Headline")
        doc.table(["condition", "tests per policy", "assembled, base / VGS",
                   "std of times [s], base / VGS", "gain in total time",
                   "paper's gain: total time of its 1000 tests, none reported failed",
                   "same, without failed attempts", "gain on mean times", "gain in alignment"],
                  head_rows)
        doc.p("Gains of VGS over the baseline with paired-bootstrap 95 % intervals. Total "
              "time: the summed assembly times of all tests, each failed attempt counted until "
              "it was given up" + _timeouts_text(meta) + "; without failed attempts: the "
              "summed times of the successes alone (like with like only where both policies "
              "assemble about as many tests); mean times: the mean time of the "
              "successes; alignment: the mean time of the alignment phase of the successes, "
              "the phase the paper studies. The paper reports one gain, on its total time over "
              "1000 tests, none of which it reports failed: our like measure is the gain in "
              "total time beside it; the standard deviations beside the "
              "paper's are in each condition's table below (its stability claim).")
    verdicts = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        part = df[df["condition"] == condition]
        base, vgs = part[part["policy"] == "baseline"], part[part["policy"] == "vgs"]
        if len(base) and len(vgs):
            verdicts.append(_verdict(condition, efficiency_gain(base, vgs), summarize(base),
                                     summarize(vgs),
                                     efficiency_gain(base, vgs, measure=TOTAL_GAIN)))
    if verdicts:
        doc.p("What this run measured:")
        doc.items(verdicts)


def _com_offset_rows(df: pd.DataFrame, policies: list[str]) -> list[list[str]]:
    """A condition whose pegs' centre of mass is off the middle (``com``): the mean |grasp
    offset| from the true centre of mass per policy (ground truth, analysis only); none on
    uniform pegs, where it equals the offset from the middle."""
    if not com_shifted(df):
        return []
    cells = []
    for policy in policies:
        offsets = df.loc[df["policy"] == policy, "grasp_offset_com_mm"].dropna().abs()
        cells.append(_f(float(offsets.mean()), 1) if len(offsets) else "-")
    return [["mean distance of the grasp from the centre of mass [mm]", *cells, "-", "-"]]


def _condition_section(doc: Doc, df: pd.DataFrame, table: pd.DataFrame, condition: str,
                       figures: Path) -> None:
    """One condition: every policy's numbers beside the paper's, its times, its failures."""
    part = table[table["condition"] == condition].set_index("policy")
    policies = list(part.index)
    doc.h(2, CONDITION_TITLES[condition])
    header = ["metric", *(f"{p} (ours)" for p in policies), "baseline (paper)",
              "VGS (paper)"]

    def row(label: str, key: str, digits: int, paper_key: str | None = None) -> list[str]:
        pk = paper_key or key
        return [label, *(_f(part.loc[p, key], digits) for p in policies),
                _paper(condition, pk, 0, digits), _paper(condition, pk, 1, digits)]

    rows = [
        row("test assemblies", "episodes", 0),
        [*row("success rate", "success_rate", 3)[:-2], "-", "-"],
        [*row("grasp success rate", "grasp_success_rate", 3)[:-2], "-", "-"],
        row("total assembly time of the successes [h]", "time_total_h", 2),
        row("total time of all assembly attempts, failed ones until given up [h]",
            "time_all_h", 2, paper_key="time_total_h"),
        row("mean [s]", "time_mean_s", 2),
        [*row("median [s]", "time_median_s", 2)[:-2], "-", "-"],
        row("min [s]", "time_min_s", 1),
        row("max [s]", "time_max_s", 1),
        row("standard deviation [s]", "time_std_s", 4),
        [*row("assembly time per assembled peg, failed attempts included [s]",
              "time_per_assembled_s", 1)[:-2], "-", "-"],
        [*row("mean distance of the grasp from the middle [mm]", "abs_grasp_offset_mean_mm",
              1)[:-2], "-", "-"],
        *_com_offset_rows(df[df["condition"] == condition], policies),
        *([label,
           *(Gain(part.loc[p, f"{m.name}_pct"], part.loc[p, f"{m.name}_ci_low"],
                  part.loc[p, f"{m.name}_ci_high"], True, 0).text()
             if p != "baseline" else "-" for p in policies),
           "-", _paper_gain_text(condition) if m is TOTAL_GAIN else "-"]
          for m, label in ((TOTAL_GAIN, "gain in total time [%] (95 % CI)"),
                           (SUCCESS_TOTAL_GAIN, "gain in total time without failed "
                                                "attempts [%]"),
                           (MEAN_GAIN, "gain on the mean time [%]"),
                           (ALIGN_GAIN, "gain in the alignment phase [%]"))),
    ]
    doc.table(header, rows)
    fig = plot_times(df, condition, figures / f"times_{condition}.png")
    doc.img(fig, f"Assembly times, {CONDITION_TITLES[condition]}")
    reasons = df[(df["condition"] == condition) & ~df["assembly_success"].astype(bool)]
    if len(reasons):
        counts = reasons.groupby(["policy", "failure_reason"]).size()
        doc.p("Failures: " + "; ".join(f"{p} {r} x{n}" for (p, r), n in counts.items())
              + ".")


def _training_section(doc: Doc, out: Path, figures: Path) -> None:
    """The training runs: their table, learning curves and Q heat maps (paper Fig. 7)."""
    runs = [r for r in train_folders(out) if (r / "episodes.csv").exists()]
    if runs:
        doc.h(2, "Training")
        doc.p(ONE_STEP_TARGET)
        doc.table(["run", "episodes", "grasp success", "assembly success (last 20 %)",
                   "mean |offset| last 20 % [mm]", "threshold [s]", "delta-Q converged"],
                  _training_rows(out))
        from vgs.analysis.curves import plot_curves

        curves = figures / "learning_curves.png"
        plot_curves(runs, curves, window=max(5, min(50, len(read_table(
            runs[0] / "episodes.csv", "train")) // 8)))
        doc.img(curves, "Learning curves (moving means) and grasp offsets during training")
        from vgs.analysis.heatmap import plot_heatmaps

        for run in runs:
            if holds_network(run):
                fig = plot_heatmaps(run, figures / f"heatmap_{run.name}.png", scenes=1)
                doc.img(fig, f"Q heat maps of {run.name}, untrained beside trained "
                             "(paper Fig. 7)")


def _sweep_section(doc: Doc, out: Path) -> None:
    """The grasp-position sweep of the reproduction, if it ran one."""
    sweep_png = out / "sweep" / "sweep.png"
    if sweep_png.exists():
        doc.h(2, "Grasp-position sweep")
        summary = out / "sweep" / "summary.json"
        if summary.exists():
            s = read_json(summary, kind=object)
            rows = [[_f(r["offset_mm"], 1), f"{r['successes']}/{r['n']}",
                     _f(r["time_mean_s"]), _f(r["time_std_s"])]
                    for r in (s if isinstance(s, list) else s.get("offsets", []))]
            if rows:
                doc.table(["offset [mm]", "success", "mean time [s]", "std [s]"], rows)
        doc.img(sweep_png, "Assembly time against a fixed grasp offset (with eq. 2, 3)")




