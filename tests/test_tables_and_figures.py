"""Tables and figures a researcher would cite (issue 42, items 5 and 7): times written to the
ms, one colour per policy in every figure, the report's title kept on a re-run with the gain
in total time in results.csv, ``vgs train --workers``."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

import vgs
from vgs.analysis.palette import POLICY_COLORS, policy_color
from vgs.cli.options import config_from_args, flag_overrides
from vgs.cli.parser import build_parser
from vgs.columns import rounded, rounded_rows

FIGURES = ("analysis/reportfigures.py", "analysis/curves.py", "analysis/heatmap.py",
           "analysis/seeds.py", "analysis/sweepfigure.py", "tools/demofigure.py", "tools/demo.py")


def test_times_are_written_to_the_ms_and_nothing_else_moves() -> None:
    df = pd.DataFrame({"assembly_time_s": [43.16000000001258, float("nan")],
                       "time_search_s": [21.070000000003, 0.0], "grasp_offset_mm": [1.23456789,
                                                                                     2.0]})
    out = rounded(df)
    assert out["assembly_time_s"].iloc[0] == 43.16 and out["time_search_s"].iloc[0] == 21.07
    assert out["grasp_offset_mm"].iloc[0] == 1.23456789 and pd.isna(out["assembly_time_s"][1])
    assert df["assembly_time_s"].iloc[0] == 43.16000000001258  # the caller's frame untouched
    (row,) = rounded_rows([{"assembly_time_s": 43.16000000001258, "failure_reason": "x"}])
    assert row == {"assembly_time_s": 43.16, "failure_reason": "x"}


def test_one_colour_per_policy_in_every_figure() -> None:
    """The figure modules take policy colours from vgs.analysis.palette; none names a
    colour of the palette's policies itself (VGS was orange in one figure, red in another)."""
    assert len(set(POLICY_COLORS.values())) == len(POLICY_COLORS)
    assert policy_color("vgs") == "tab:red" and policy_color("mine:fn") not in \
        POLICY_COLORS.values()
    root = Path(vgs.__file__).parent
    for name in FIGURES:
        text = (root / name).read_text()
        for colour in [*POLICY_COLORS.values(), "tab:orange", '"C1"', "'C1'"]:
            assert colour not in text, (name, colour)


def test_train_takes_workers_as_parallel_episodes() -> None:
    args = build_parser().parse_args(["train", "--mode", "vgs", "--out", "x", "--workers",
                                      "2", "--profile", "smoke"])
    cfg = flag_overrides(config_from_args(args), args, {"workers": "train.parallel_episodes"})
    assert cfg.train.parallel_episodes == 2


@pytest.mark.slow
def test_report_rerun_keeps_its_title_and_results_have_total_gain(quick_reproduction,
                                                                   tmp_path: Path) -> None:
    from vgs.analysis.report import build_report

    assert quick_reproduction.proc.returncode == 0, quick_reproduction.proc.stderr
    src = quick_reproduction.out
    assert (src / "report.md").read_text().startswith("# VGS reproduction report (quick "
                                                       "profile)")
    copy = tmp_path / "repro"
    shutil.copytree(src / "eval", copy / "eval")
    shutil.copy(src / "reproduce.json", copy)
    report = build_report(copy)  # as vgs report DIR does, no --title
    assert report.read_text().splitlines()[0] == "# VGS reproduction report (quick profile)"
    columns = pd.read_csv(copy / "results.csv").columns
    assert {"total_gain_pct", "success_total_gain_pct", "gain_pct", "align_gain_pct"} \
        <= set(columns)


def test_grasp_positions_show_the_centre_of_mass_where_it_is_off_the_middle(
        tmp_path: Path) -> None:
    """A condition whose peg's centre of mass is off the middle gets a second row of
    histograms, offsets from the centre of mass; a uniform peg's figure keeps one row."""
    import matplotlib.image

    from vgs.analysis.reportfigures import plot_grasp_positions

    rows = [{"condition": c, "policy": p, "grasp_success": True, "grasp_offset_mm": off,
             "grasp_offset_com_mm": off - shift, "peg_com_shift_mm": shift}
            for c, shift in (("nominal", 0.0), ("com", 20.0))
            for p, off in (("vgs", 18.0), ("center", 0.5), ("com-oracle", 20.2))]
    df = pd.DataFrame(rows)
    one = plot_grasp_positions(df[df["condition"] == "nominal"], tmp_path / "one.png")
    two = plot_grasp_positions(df, tmp_path / "two.png")
    h1 = matplotlib.image.imread(one).shape[0]
    h2 = matplotlib.image.imread(two).shape[0]
    assert h2 == 2 * h1


def test_the_report_sets_each_learned_policy_against_the_references(tmp_path: Path) -> None:
    """A folder that evaluated a reference policy gets the section "Against the reference
    policies": one row per condition, reference and learned policy, on the same scenes."""
    from vgs.analysis.report import build_report

    folder = tmp_path / "report"
    shutil.copytree(Path(__file__).parent / "data" / "report_small", folder)
    text = build_report(folder).read_text()
    section = text.split("## Against the reference policies")[1].split("\n## ")[0]
    rows = [line for line in section.splitlines() if line.startswith("| ")][1:]
    assert rows and all("| center |" in row for row in rows)
    assert {row.split("|")[3].strip().split()[0] for row in rows} == {"baseline", "vgs"}


def test_the_report_reads_a_condition_the_paper_did_not_test(tmp_path: Path) -> None:
    """A run tested on `com` alone (issue 55's protocol): the paper gives no gain for it, so
    its column reads "-" and the verdict says so, where a KeyError stopped the report."""
    from vgs.analysis.report import build_report

    folder = tmp_path / "report"
    for policy in ("baseline", "vgs", "center"):
        src = Path(__file__).parent / "data" / "report_small" / "eval" / policy / "nominal"
        df = pd.read_parquet(src / "episodes.parquet")
        df["condition"] = "com"
        df["peg_com_shift_mm"] = 20.0
        df["grasp_offset_com_mm"] = df["grasp_offset_mm"] - 20.0
        (folder / "eval" / policy / "com").mkdir(parents=True)
        df.to_parquet(folder / "eval" / policy / "com" / "episodes.parquet")
    text = build_report(folder).read_text()
    head = text.split("## Headline")[1].split("\n## ")[0]
    (row,) = [line for line in head.splitlines() if line.startswith("| com |")]
    assert row.split("|")[6].strip() == "-"
    # The distance of the grasps from the true centre of mass beside that from the middle.
    section = text.split("\n## Centre of mass 20 mm")[1].split("\n## ")[0]
    (middle,) = [line for line in section.splitlines() if "from the middle [mm]" in line]
    (com,) = [line for line in section.splitlines() if "from the centre of mass [mm]" in line]
    eval_dir = Path(__file__).parent / "data" / "report_small" / "eval"
    offsets = pd.read_parquet(eval_dir / "center" / "nominal" / "episodes.parquet")[
        "grasp_offset_mm"].dropna()
    (header,) = [line for line in section.splitlines() if line.startswith("| metric |")]
    at = [c.strip() for c in header.split("|")].index("center (ours)")
    assert middle.split("|")[at].strip() == f"{offsets.abs().mean():.1f}" == "0.5"
    assert com.split("|")[at].strip() == f"{(offsets - 20.0).abs().mean():.1f}" == "20.2"
    # Its verdict, with enough successes to compare (the small table has too few).
    from vgs.analysis.report import _verdict
    from vgs.analysis.stats import Gain

    stats = {"success_rate": 0.9, "successes": 900, "episodes": 1000, "time_std_s": 5.0}
    verdict = _verdict("com", Gain(10.0, 8.0, 12.0, True, 900), stats, stats,
                       Gain(20.0, 17.0, 23.0, True, 1000))
    assert "+20.00 % [+17.00, +23.00] (a condition the paper did not test)" in verdict
