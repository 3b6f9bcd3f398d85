"""Configuration from the command line (in process): flags, --set, and the semantic checks."""

from __future__ import annotations

import pytest

from vgs.cli import build_parser, config_from_args, main, parse_value
from vgs.errors import ConfigError


def cfg_for(*argv: str):
    return config_from_args(build_parser().parse_args(["export-scene", *argv]))


def test_flags_and_set_pairs() -> None:
    cfg = cfg_for("--peg-mass", "0.6", "--peg-length", "0.12", "--clearance", "0.0008",
                  "--hole-depth", "0.05", "--gripper-force", "30", "--set",
                  "assembly.press_force=12", "--set", "cell.hole.randomize=False",
                  "--profile", "smoke")
    assert cfg.name == "smoke"
    assert cfg.cell.peg.mass == 0.6 and cfg.cell.peg.length == 0.12
    assert cfg.cell.hole.clearance == 0.0008 and cfg.cell.hole.depth == 0.05
    assert cfg.cell.gripper.force == 30.0
    assert cfg.assembly.press_force == 12 and cfg.cell.hole.randomize is False


def test_peg_diameter_keeps_the_hole_made_for_the_nominal_peg() -> None:
    cfg = cfg_for("--peg-diameter", "0.0305")
    assert cfg.cell.hole.peg_diameter == pytest.approx(0.030)
    assert cfg.cell.hole.diameter == pytest.approx(0.031)


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (("--peg-diameter", "0.0315", "--clearance", "0.001"), "hole.clearance"),
        (("--peg-diameter", "0.031"), "hole.clearance"),
        (("--clearance", "0"), "hole.clearance"),
        (("--peg-mass", "-1"), "cell.peg.mass"),
        (("--hole-depth", "0.02"), "hole.depth"),
        (("--profile", "huge"), "profile"),
        (("--set", "cell.peg.mass"), "set"),
        (("--set", "cell.hole.segments='many'"), "cell.hole.segments"),
    ],
)
def test_bad_input_names_the_field(argv: tuple[str, ...], field: str) -> None:
    with pytest.raises(ConfigError) as info:
        cfg_for(*argv)
    assert info.value.field == field


def test_parse_value() -> None:
    assert parse_value("0.5") == 0.5
    assert parse_value("(1, 2)") == (1, 2)
    assert parse_value("False") is False
    assert parse_value("light") == "light"


def test_tuple_fields_take_unquoted_items() -> None:
    from vgs.cli import apply_override
    from vgs.config import profile

    cfg = profile("smoke")
    assert apply_override(cfg, "reproduce.conditions", "(nominal,)").reproduce.conditions == (
        "nominal",)
    assert apply_override(cfg, "reproduce.conditions",
                          parse_value("nominal,mass")).reproduce.conditions == ("nominal", "mass")
    assert apply_override(cfg, "reproduce.train_seeds",
                          parse_value("(0, 1)")).reproduce.train_seeds == (0, 1)
    assert apply_override(cfg, "reproduce.reference_policies",
                          parse_value("()")).reproduce.reference_policies == ()


def test_main_reports_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--peg-mass", "-1"]) == 2
    err = capsys.readouterr().err
    assert err == "vgs: error: --peg-mass: must lie in [0.001, 50], got -1.0\n"


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    from vgs import __version__
    from vgs.cli import main

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    from vgs.revision import source_revision

    assert capsys.readouterr().out.strip() == f"vgs {__version__} (source {source_revision()})"


# -- each command takes only the flags it uses ----------------------------------------------

# The positional arguments and required flags of each command, so that it parses.
REQUIRED = {
    "demo": [], "sweep": [], "export-scene": [], "export-policy": ["RUN", "--out", "w.pt"],
    "model-info": [], "train": ["--mode", "vgs", "--out", "x"], "heatmap": ["RUN", "--out", "x"],
    "curves": ["RUN", "--out", "x"], "evaluate": ["--policy", "center", "--out", "x"],
    "reproduce": ["--out", "x"], "report": ["DIR"], "seeds": ["DIR", "--out", "x"],
    "grasp-sites": ["DIR"], "com-fit": ["DIR"], "status": ["DIR"], "config": [],
}
# Commands that build their configuration from a profile and the cell's override flags.
CONFIGURED = {"demo", "sweep", "export-scene", "train", "evaluate", "reproduce", "config"}
# Commands that draw a progress bar (tqdm: vgs.experiments.sweep, .train, .evaluate,
# vgs.analysis.graspsites) or progress lines (demo: vgs.tools.demo.EpisodeTicker).
PROGRESS_BARS = {"sweep", "train", "evaluate", "reproduce", "grasp-sites", "demo"}


def _takes(command: str, *flags: str) -> bool:
    import argparse

    from vgs.cli import UsageError

    try:
        _, extra = build_parser().parse_known_args([command, *REQUIRED[command], *flags])
    except (UsageError, argparse.ArgumentError):
        return False
    return not extra


def test_the_table_names_every_command() -> None:
    import argparse

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == set(REQUIRED)


@pytest.mark.parametrize("command", sorted(REQUIRED))
def test_each_command_takes_only_the_flags_it_uses(command: str) -> None:
    assert _takes(command, "--peg-mass", "0.6") == (command in CONFIGURED)
    assert _takes(command, "--profile", "smoke") == (command in CONFIGURED | {"model-info"})
    assert _takes(command, "--config", "c.json") == (command in CONFIGURED | {"model-info"})
    assert _takes(command, "--set", "network.backbone=light") == (
        command in CONFIGURED | {"model-info"})
    assert _takes(command, "--no-progress") == (command in PROGRESS_BARS)


def test_every_module_with_a_progress_bar_is_known() -> None:
    """A new progress bar needs --no-progress on its commands: add them to PROGRESS_BARS."""
    from pathlib import Path

    import vgs

    root = Path(vgs.__file__).parent
    with_bar = {p.relative_to(root).as_posix() for p in root.rglob("*.py")
                if "tqdm" in p.read_text()}
    assert with_bar == {"experiments/sweep.py", "experiments/train.py",
                        "experiments/evaluate.py", "analysis/graspsites.py"}


def test_report_refuses_a_configuration_flag(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", "DIR", "--peg-mass", "5"]) == 2
    assert capsys.readouterr().err == ("vgs: error: report: does not take --peg-mass 5 (vgs "
                                       "report --help lists what it takes)\n")


def test_model_info_takes_network_keys_only() -> None:
    args = build_parser().parse_args(["model-info", "--set", "network.num_rotations=4"])
    assert config_from_args(args).network.num_rotations == 4
    args = build_parser().parse_args(["model-info", "--set", "train.episodes=4"])
    with pytest.raises(ConfigError) as info:
        config_from_args(args)
    assert info.value.field == "set" and "network.*" in info.value.message


# -- vgs config: every key, its value and its documentation -----------------------------------


@pytest.mark.parametrize("name", ["smoke", "quick", "medium", "paper"])
def test_every_settable_key_has_a_doc(name: str) -> None:
    from vgs.config import profile
    from vgs.configdoc import settings

    items = settings(profile(name))
    assert [s.key for s in items if not s.doc] == []
    keys = [s.key for s in items]
    assert len(keys) == len(set(keys)) and "network.backbone" in keys
    assert "cell.peg" not in keys  # sections are not keys


def test_field_docs_and_first_sentences() -> None:
    from vgs.config import HoleConfig, NetworkConfig
    from vgs.configdoc import field_docs, first_sentence, format_settings, settings

    docs = field_docs(HoleConfig)
    assert docs["depth"] == "Depth of the hole [m]; must exceed the insertion depth K."
    assert docs["segments"].startswith("Number of convex wedges") and "  " not in docs["segments"]
    assert first_sentence(docs["segments"]) == ("Number of convex wedges that approximate the "
                                                "round hole.")
    assert first_sentence("Displace it (paper 3.2), i.e. within r. Next.") == (
        "Displace it (paper 3.2), i.e. within r.")
    assert first_sentence("A (one. Two) b. C") == "A (one. Two) b."
    text = format_settings(settings(NetworkConfig(backbone="light", weights=None)))
    assert "backbone" in text and "= light " in text and "= None " in text
    assert "# densenet121 (paper) or light (fast CPU runs)." in text  # markup removed


def test_config_prints_what_set_resolves(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["config", "--profile", "smoke", "--set", "assembly.press_force=4",
                 "--set", "reproduce.conditions=nominal,mass"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("# profile smoke, resolved")
    lines = {line.split(" = ")[0].strip(): line for line in out.splitlines()}
    assert "= 4.0 " in lines["assembly.press_force"]
    assert "= ('nominal', 'mass') " in lines["reproduce.conditions"]


# -- vgs demo: progress while the episode runs, no silent overwrite ---------------------------


def test_demo_ticker_reports_the_clock_while_it_runs() -> None:
    import time

    from vgs.tools.demo import EpisodeTicker

    seen: list[tuple[float, float]] = []
    clock = iter(range(1000))
    with EpisodeTicker(lambda: float(next(clock)), lambda s, w: seen.append((s, w)),
                       interval=0.01):
        time.sleep(0.2)
    count = len(seen)
    time.sleep(0.05)
    assert len(seen) == count >= 3  # reported while inside, stopped on leaving
    assert [s for s, _ in seen] == sorted(s for s, _ in seen) and seen[-1][1] > 0


def test_demo_refuses_to_overwrite_before_the_episode(
        tmp_path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "demo.png").write_bytes(b"old")
    assert main(["demo", "--profile", "smoke", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "demo.png exists; add --force" in err
    video = tmp_path / "v.gif"
    video.write_bytes(b"old")
    assert main(["demo", "--out", str(tmp_path / "new"), "--video", str(video)]) == 2
    assert "v.gif exists" in capsys.readouterr().err
    assert (tmp_path / "demo.png").read_bytes() == b"old" and not (tmp_path / "new").exists()
