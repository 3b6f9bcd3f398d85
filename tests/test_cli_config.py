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
        (("--peg-mass", "-1"), "peg.mass"),
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
    assert err == "vgs: error: peg.mass: must be a positive number, got -1.0\n"


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    from vgs import __version__
    from vgs.cli import main

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"vgs {__version__}"
