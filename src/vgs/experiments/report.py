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

import base64
import html
import json
import math
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from vgs.checkpoint import atomic_write_text  # noqa: E402
from vgs.errors import ConfigError  # noqa: E402
from vgs.experiments.evaluate import CONDITIONS, summarize  # noqa: E402
from vgs.runfolder import read_json, read_table  # noqa: E402

BOOTSTRAP_RESAMPLES = 2000
# Fewer successful assemblies than this per policy: times are not compared (no verdict, no CI).
MIN_SUCCESSES = 5
LEARNED = ("baseline", "vgs")
CONDITION_TITLES = {
    "nominal": "Nominal peg (paper Fig. 8)",
    "mass": "Mass +-15 % (paper Fig. 9)",
    "length": "Length 85-115 %, mass following (paper Fig. 10)",
}



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


# -- statistics ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Gain:
    """Efficiency gain of VGS over the baseline [%] with its bootstrap 95 % interval."""

    value: float
    low: float
    high: float
    paired: bool
    n: int

    def text(self) -> str:
        if not math.isfinite(self.value):
            return "n/a"
        if not math.isfinite(self.low):
            return f"{self.value:+.2f} % [too few successes]"
        return f"{self.value:+.2f} % [{self.low:+.2f}, {self.high:+.2f}]"


def _mean_success(times: np.ndarray, ok: np.ndarray) -> float:
    return float(times[ok].mean()) if ok.any() else math.nan


def time_arrays(df: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """``(assembly_time_s, assembly_success)`` of an evaluation table, ordered by episode
    index."""
    df = df.sort_values("index")
    return df["assembly_time_s"].to_numpy(float), df["assembly_success"].to_numpy(bool)


def gain_pct(tb: np.ndarray, ob: np.ndarray, tv: np.ndarray, ov: np.ndarray) -> float:
    """``100 (T_base - T_vgs) / T_base`` on the mean times of the successes (NaN without any)."""
    mb, mv = _mean_success(tb, ob), _mean_success(tv, ov)
    return 100.0 * (mb - mv) / mb if math.isfinite(mb) and math.isfinite(mv) else math.nan


def efficiency_gain(base: pd.DataFrame, vgs: pd.DataFrame, resamples: int = BOOTSTRAP_RESAMPLES,
                    seed: int = 0) -> Gain:
    """``100 (T_base - T_vgs) / T_base`` on mean successful assembly times, bootstrap 95 % CI.

    The interval is NaN when either policy has fewer than :data:`MIN_SUCCESSES` successful
    assemblies (a mean of one or two times has no useful interval). Episodes are paired by
    ``index`` when both tables hold the same indices (the same scenes); otherwise each table is
    resampled on its own.
    """
    base = base.sort_values("index")
    vgs = vgs.sort_values("index")
    tb, ob = time_arrays(base)
    tv, ov = time_arrays(vgs)
    value = gain_pct(tb, ob, tv, ov)
    paired = list(base["index"]) == list(vgs["index"])
    if not math.isfinite(value) or min(ob.sum(), ov.sum()) < MIN_SUCCESSES:
        return Gain(value, math.nan, math.nan, paired, len(base))
    rng = np.random.default_rng(seed)
    gains = np.empty(resamples)
    for b in range(resamples):
        ib = rng.integers(len(tb), size=len(tb))
        iv = ib if paired else rng.integers(len(tv), size=len(tv))
        gains[b] = gain_pct(tb[ib], ob[ib], tv[iv], ov[iv])
    gains = gains[np.isfinite(gains)]
    low, high = (np.percentile(gains, [2.5, 97.5]) if gains.size else (math.nan, math.nan))
    return Gain(value, float(low), float(high), paired, len(base))


# -- loading -------------------------------------------------------------------------------------


def load_results(out: Path) -> pd.DataFrame:
    """All evaluation tables under ``out/eval`` in one frame, in the column vocabulary of
    :mod:`vgs.columns` (tables published with the legacy names are renamed on load).

    Raises:
        ConfigError: If there are none.
    """
    tables = sorted((out / "eval").glob("*/*/episodes.parquet"))
    if not tables:
        raise ConfigError("report", f"no evaluation results under {out / 'eval'} "
                                    "(expected eval/<policy>/<condition>/episodes.parquet)")
    return pd.concat([read_table(t) for t in tables], ignore_index=True)


def hosts_note(df: pd.DataFrame) -> str:
    """A sentence on the hosts the test episodes ran on (``host_cpu``, ``mujoco_version``
    columns; tables written before they were recorded have none): empty when not recorded,
    a warning naming the evaluations whose episodes come from several hosts."""
    if "host_cpu" not in df.columns:
        return ""
    from vgs.runfolder import hosts_of

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
                "differently on another host; compare such results with care.")
    names = hosts_of(df[["host_cpu", "mujoco_version"]].to_dict("records"))
    return f"All test episodes ran on one host: {names[0]}." if names else ""


def policy_order(policies: list[str]) -> list[str]:
    """Learned policies first (baseline, vgs), then the references."""
    return [p for p in LEARNED if p in policies] + sorted(p for p in policies if p not in LEARNED)


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
            gain = (efficiency_gain(base, mine) if policy != "baseline" and len(base)
                    else Gain(math.nan, math.nan, math.nan, False, 0))
            rows.append({"condition": condition, "policy": policy, **s,
                         "gain_pct": gain.value, "gain_ci_low": gain.low,
                         "gain_ci_high": gain.high})
    return pd.DataFrame(rows)


# -- figures -------------------------------------------------------------------------------------

COLORS = {"baseline": "tab:blue", "vgs": "tab:red", "center": "tab:gray", "random": "tab:green"}


def _color(policy: str) -> str:
    return COLORS.get(policy, "tab:purple")


def plot_times(df: pd.DataFrame, condition: str, path: Path) -> Path:
    """Assembly time of every successful test episode (left) and their distribution (right)."""
    part = df[(df["condition"] == condition) & df["assembly_success"].astype(bool)]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    times_all = part["assembly_time_s"].to_numpy(float)
    bins = (np.linspace(times_all.min(), times_all.max(), 30) if times_all.size > 1 else 10)
    for policy in policy_order(sorted(set(df["policy"]))):
        mine = part[part["policy"] == policy]
        if mine.empty:
            continue
        t = mine["assembly_time_s"].to_numpy(float)
        ax1.plot(mine["index"], t, ".", ms=4, alpha=0.7, color=_color(policy),
                 label=f"{policy} (mean {t.mean():.1f} s, n={t.size})")
        ax1.axhline(t.mean(), color=_color(policy), lw=1)
        ax2.hist(t, bins=bins, alpha=0.45, color=_color(policy), label=policy)
    ax1.set_xlabel("test episode")
    ax1.set_ylabel("assembly time [s, simulated]")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("assembly time [s, simulated]")
    ax2.set_ylabel("episodes")
    ax2.legend(fontsize=8)
    fig.suptitle(f"Assembly time, successful tests: {CONDITION_TITLES[condition]}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_grasp_positions(df: pd.DataFrame, path: Path) -> Path:
    """Where each policy grasped: the realised offset from the centre of mass along the peg."""
    conditions = [c for c in CONDITIONS if c in set(df["condition"])]
    fig, axes = plt.subplots(1, len(conditions), figsize=(4.5 * len(conditions), 3.6),
                             squeeze=False)
    bins = np.linspace(-60, 60, 41)
    for ax, condition in zip(axes[0], conditions, strict=True):
        part = df[(df["condition"] == condition) & df["grasp_success"].astype(bool)]
        for policy in policy_order(sorted(set(df["policy"]))):
            off = part.loc[part["policy"] == policy, "grasp_offset_mm"].dropna()
            if off.empty:
                continue
            ax.hist(off, bins=bins, alpha=0.45, color=_color(policy),
                    label=f"{policy} (mean |l| {off.abs().mean():.1f} mm)")
        ax.set_title(condition)
        ax.set_xlabel("grasp offset from the centre of mass [mm]")
        ax.set_ylabel("grasps")
        ax.legend(fontsize=7)
    fig.suptitle("Where each policy grasps along the peg (test episodes)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# -- the document --------------------------------------------------------------------------------


class Doc:
    """Report content as blocks, rendered to Markdown and to self-contained HTML."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.blocks: list[tuple[str, Any]] = []

    def h(self, level: int, text: str) -> None:
        self.blocks.append(("h", (level, text)))

    def p(self, text: str) -> None:
        self.blocks.append(("p", text))

    def items(self, lines: list[str]) -> None:
        self.blocks.append(("ul", lines))

    def table(self, header: list[str], rows: list[list[str]]) -> None:
        self.blocks.append(("table", (header, rows)))

    def img(self, path: Path, caption: str) -> None:
        self.blocks.append(("img", (path, caption)))

    def markdown(self) -> str:
        out: list[str] = []
        for kind, value in self.blocks:
            if kind == "h":
                out.append("#" * value[0] + " " + value[1])
            elif kind == "p":
                out.append(value)
            elif kind == "ul":
                out.append("\n".join(f"- {line}" for line in value))
            elif kind == "table":
                header, rows = value
                out.append("\n".join(["| " + " | ".join(header) + " |",
                                      "|" + "|".join("---" for _ in header) + "|",
                                      *("| " + " | ".join(r) + " |" for r in rows)]))
            elif kind == "img":
                path, caption = value
                out.append(f"![{caption}]({path.relative_to(self.root).as_posix()})\n\n"
                           f"*{caption}*")
        return "\n\n".join(out) + "\n"

    def html(self, title: str) -> str:
        def inline(text: str) -> str:
            t = html.escape(text)
            parts = t.split("`")
            t = "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))
            parts = t.split("**")
            return "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))

        body: list[str] = []
        for kind, value in self.blocks:
            if kind == "h":
                body.append(f"<h{value[0]}>{inline(value[1])}</h{value[0]}>")
            elif kind == "p":
                body.append(f"<p>{inline(value)}</p>")
            elif kind == "ul":
                body.append("<ul>" + "".join(f"<li>{inline(v)}</li>" for v in value) + "</ul>")
            elif kind == "table":
                header, rows = value
                head = "".join(f"<th>{inline(c)}</th>" for c in header)
                trs = "".join("<tr>" + "".join(f"<td>{inline(c)}</td>" for c in r) + "</tr>"
                              for r in rows)
                body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{trs}</tbody></table>")
            elif kind == "img":
                path, caption = value
                data = base64.b64encode(path.read_bytes()).decode()
                body.append(f'<figure><img alt="{html.escape(caption)}" '
                            f'src="data:image/png;base64,{data}"/>'
                            f"<figcaption>{inline(caption)}</figcaption></figure>")
        style = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.45}"
                 "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
                 "padding:3px 8px;text-align:right}th{background:#eee}td:first-child{text-align:"
                 "left}img{max-width:100%}figcaption{font-style:italic;color:#444}"
                 "code{background:#f3f3f3;padding:0 3px}")
        return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
                f"</title><style>{style}</style></head><body>{''.join(body)}</body></html>\n")


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


def _verdict(condition: str, gain: Gain, base: dict[str, Any], vgs: dict[str, Any]) -> str:
    success = (f"success {base['success_rate']:.1%} (baseline, {base['successes']} of "
               f"{base['episodes']}) vs {vgs['success_rate']:.1%} (VGS, {vgs['successes']} of "
               f"{vgs['episodes']})")
    if not math.isfinite(gain.low):
        return (f"**{condition}**: too few successful assemblies to compare times (at least "
                f"{MIN_SUCCESSES} per policy needed); {success}.")
    paper = PAPER[condition]["gain"]
    if gain.low > 0:
        verdict = "VGS was faster than the baseline (the 95 % interval excludes 0)"
    elif gain.high < 0:
        verdict = "VGS was SLOWER than the baseline (the 95 % interval excludes 0)"
    else:
        verdict = "no significant difference between VGS and the baseline (the 95 % interval " \
                  "includes 0)"
    return (f"**{condition}**: {verdict}: gain {gain.text()} (paper: {paper:+.2f} %); "
            f"{success}; std {_f(base['time_std_s'], 2)} vs {_f(vgs['time_std_s'], 2)} s.")


ONE_STEP_TARGET = (
    "Each grasp is a terminal one-step episode (the next peg is placed independently of it), "
    "so the training target is y = R: gamma and the target network never affect learning, "
    "Delta Q = |R - Q_eva| of the grasp's own update, and a run counts as delta-Q converged "
    "when that Delta Q stayed below `agent.delta_q_threshold` in each of its last "
    "`agent.delta_q_window` episodes (the window's maximum, not its mean).")


def _training_rows(out: Path) -> list[list[str]]:
    rows = []
    for run in sorted((out / "train").glob("*")):
        csv_path = run / "episodes.csv"
        if not csv_path.exists():
            continue
        ep = read_table(csv_path)
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


def build_report(out: Path, title: str = "VGS reproduction report") -> Path:
    """Write ``report.md``, ``report.html``, ``results.csv`` and figures into ``out``.

    Raises:
        ConfigError: If ``out`` holds no evaluation results.
    """
    df = load_results(out)
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    table = results_table(df)
    table.to_csv(out / "results.csv", index=False)
    meta = read_json(out / "reproduce.json") if (out / "reproduce.json").exists() else {}

    doc = Doc(out)
    doc.h(1, title)
    if meta:
        doc.p(f"Profile `{meta.get('profile')}`, command `{meta.get('command')}`, on "
              f"{meta.get('machine', '?')}; git {str(meta.get('git_revision', '?'))[:10]}; "
              f"finished {meta.get('finished', '?')}.")
        stages = meta.get("stage_wall_s", {})
        if stages:
            doc.p("Wall time per stage: " + ", ".join(
                f"{k} {v / 60:.1f} min" for k, v in stages.items()) + ".")
    doc.p("All times are **simulated** seconds of successful assemblies in our MuJoCo cell "
          "(UR5 + RG2, F/T-driven compliance). The paper's absolute times come from its own "
          "simulator and controller; compare the gains, spreads and the direction of effects, "
          "not the absolute seconds. Failed episodes count in the success rate only. Gain = "
          "(T_base - T_VGS) / T_base on mean times, 95 % paired-bootstrap interval.")

    host_note = hosts_note(df)
    if host_note:
        doc.p(host_note)

    head_rows = []
    for condition in [c for c in CONDITIONS if c in set(table["condition"])]:
        part = table[table["condition"] == condition].set_index("policy")
        if not {"baseline", "vgs"} <= set(part.index):
            continue
        g = part.loc["vgs"]
        gain = Gain(g["gain_pct"], g["gain_ci_low"], g["gain_ci_high"], True, 0)
        head_rows.append([condition, str(int(part.loc["baseline", "episodes"])),
                          _f(part.loc["baseline", "time_mean_s"]), _f(g["time_mean_s"]),
                          f"{part.loc['baseline', 'success_rate']:.1%} / "
                          f"{g['success_rate']:.1%}",
                          gain.text(), f"{PAPER[condition]['gain']:+.2f} %"])
    if head_rows:
        doc.h(2, "Headline")
        doc.table(["condition", "tests per policy", "baseline mean [s]", "VGS mean [s]",
                   "success base / VGS", "gain (ours, 95 % CI)", "gain (paper)"], head_rows)
    verdicts = []
    for condition in [c for c in CONDITIONS if c in set(df["condition"])]:
        part = df[df["condition"] == condition]
        base, vgs = part[part["policy"] == "baseline"], part[part["policy"] == "vgs"]
        if len(base) and len(vgs):
            verdicts.append(_verdict(condition, efficiency_gain(base, vgs), summarize(base),
                                     summarize(vgs)))
    if verdicts:
        doc.p("What this run measured:")
        doc.items(verdicts)

    for condition in [c for c in CONDITIONS if c in set(table["condition"])]:
        part = table[table["condition"] == condition].set_index("policy")
        policies = list(part.index)
        doc.h(2, CONDITION_TITLES[condition])
        header = ["metric", *(f"{p} (ours)" for p in policies), "baseline (paper)",
                  "VGS (paper)"]

        def row(label: str, key: str, digits: int, paper_key: str | None = None,
                part: pd.DataFrame = part, policies: list[str] = policies,
                condition: str = condition) -> list[str]:
            pk = paper_key or key
            return [label, *(_f(part.loc[p, key], digits) for p in policies),
                    _paper(condition, pk, 0, digits), _paper(condition, pk, 1, digits)]

        rows = [
            row("test assemblies", "episodes", 0),
            [*row("success rate", "success_rate", 3)[:-2], "-", "-"],
            [*row("grasp success rate", "grasp_success_rate", 3)[:-2], "-", "-"],
            row("total assembly time [h]", "time_total_h", 2),
            row("mean [s]", "time_mean_s", 2),
            [*row("median [s]", "time_median_s", 2)[:-2], "-", "-"],
            row("min [s]", "time_min_s", 1),
            row("max [s]", "time_max_s", 1),
            row("standard deviation [s]", "time_std_s", 4),
            [*row("assembly time per assembled peg, failed attempts included [s]",
                  "time_per_assembled_s", 1)[:-2], "-", "-"],
            [*row("mean grasp offset from the COM [mm]", "abs_grasp_offset_mean_mm", 1)[:-2],
             "-", "-"],
            ["efficiency gain over the baseline [%] (95 % CI)",
             *(Gain(part.loc[p, "gain_pct"], part.loc[p, "gain_ci_low"],
                    part.loc[p, "gain_ci_high"], True, 0).text() if p != "baseline" else "-"
               for p in policies), "-", f"{PAPER[condition]['gain']:+.2f}"],
        ]
        doc.table(header, rows)
        fig = plot_times(df, condition, figures / f"times_{condition}.png")
        doc.img(fig, f"Assembly times, {CONDITION_TITLES[condition]}")
        reasons = df[(df["condition"] == condition) & ~df["assembly_success"].astype(bool)]
        if len(reasons):
            counts = reasons.groupby(["policy", "failure_reason"]).size()
            doc.p("Failures: " + "; ".join(f"{p} {r} x{n}" for (p, r), n in counts.items())
                  + ".")
    if PAPER["nominal"]:
        doc.p("Paper means are derived from its totals (h x 3600 / 1000).")

    doc.h(2, "Where the policies grasp")
    doc.img(plot_grasp_positions(df, figures / "grasp_positions.png"),
            "Realised grasp offset along the peg axis from the centre of mass, test episodes")

    runs = [r for r in sorted((out / "train").glob("*")) if (r / "episodes.csv").exists()]
    if runs:
        doc.h(2, "Training")
        doc.p(ONE_STEP_TARGET)
        doc.table(["run", "episodes", "grasp success", "assembly success (last 20 %)",
                   "mean |offset| last 20 % [mm]", "threshold [s]", "delta-Q converged"],
                  _training_rows(out))
        from vgs.experiments.curves import plot_curves

        curves = figures / "learning_curves.png"
        plot_curves(runs, curves, window=max(5, min(50, len(read_table(
            runs[0] / "episodes.csv")) // 8)))
        doc.img(curves, "Learning curves (moving means) and grasp offsets during training")
        from vgs.experiments.heatmap import plot_heatmaps

        for run in runs:
            if (run / "checkpoint.pt").exists():
                fig = plot_heatmaps(run, figures / f"heatmap_{run.name}.png", scenes=1)
                doc.img(fig, f"Q heat maps of {run.name}, untrained beside trained "
                             "(paper Fig. 7)")

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

    atomic_write_text(out / "report.md", doc.markdown())
    atomic_write_text(out / "report.html", doc.html(title))
    return out / "report.md"


PUBLISH_POLICY_LIMIT = 10_000_000  # bytes: final networks a published run commits (light backbone)
PUBLISHED = ("reproduce.json", "report.md", "report.html", "results.csv", "figures/*.png",
             "eval/*/*/episodes.parquet", "eval/*/*/episodes.csv", "eval/*/*/summary.json",
             "train/*/episodes.csv", "train/*/run.json", "train/*/threshold.json",
             "train/*/convergence.json", "sweep/*")


def publish(out: Path, dest: Path) -> list[Path]:
    """Copy the small result files of a reproduction (no checkpoints, no TensorBoard logs, no
    journals) from ``out`` to ``dest`` (e.g. ``docs/results/quick``), keeping the layout, and
    the final networks of each finished training run as a policy folder ``dest/<mode>/``
    (``dest/<run>/`` when a mode has several runs): ``policy.pt``, ``policy.json`` and
    ``run.json``, which ``vgs evaluate --policy dest/<mode>`` loads on a fresh clone
    (:func:`vgs.experiments.export_policy.export_policy`). Networks over
    ``PUBLISH_POLICY_LIMIT`` (a DenseNet-121 policy) are not published, with a warning.

    Returns:
        The copied files.

    Raises:
        ConfigError: If ``out`` holds no report, or a policy folder in ``dest`` holds another
            run.
    """
    if not (out / "report.md").exists():
        raise ConfigError("report", f"{out} holds no report.md; run vgs report first")
    copied = []
    for pattern in PUBLISHED:
        for src in sorted(out.glob(pattern)):
            if src.is_file():
                target = dest / src.relative_to(out)
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, target)
                copied.append(target)
    finished = [run for run in sorted((out / "train").glob("*"))
                if (run / "checkpoint.pt").exists() and (run / "convergence.json").exists()]
    if finished:
        from vgs.experiments.export_policy import export_policy

        modes = [str(read_json(run / "run.json").get("mode")) for run in finished]
        for run, mode in zip(finished, modes, strict=True):
            folder = dest / (mode if modes.count(mode) == 1 else run.name)
            written = export_policy(run, folder)
            files = [written.weights, written.description, folder / "run.json"]
            size = written.weights.stat().st_size
            if size > PUBLISH_POLICY_LIMIT:
                # A DenseNet-121 policy (about 57 MB) is too large to commit: users train it.
                for f in files:
                    f.unlink(missing_ok=True)
                if folder.exists() and not any(folder.iterdir()):
                    folder.rmdir()
                warnings.warn(f"{run.name}: its final networks take {size / 1e6:.0f} MB, over "
                              f"the {PUBLISH_POLICY_LIMIT / 1e6:.0f} MB a published run commits; "
                              "not published", stacklevel=2)
                continue
            copied += files
    return copied
