"""A ceiling on every number a user can give (issue 53, item 3): every numeric flag of every
command and every count, rate, speed and time key of the configuration is bounded, and the
refusal names the bound in one line with exit code 2. The flags and keys are collected from the
parser and the configuration's documentation, so a new one is covered (or fails here)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from vgs.cli import build_parser, config_from_args, main
from vgs.cli.options import FLAG_BOUNDS, OVERRIDE_FLAGS, check_flag_bounds, parse_value, seed_arg
from vgs.config import profile
from vgs.configdoc import settings
from vgs.errors import ConfigError
from vgs.validate import BOUNDS, MAX_TIME_S, PHASE_WAITS, SEED_FIELDS, bound_text

HUGE_COUNT = 10**9
HUGE, TINY = 1e12, 1e-12
TIMED = re.compile(r"(_time|_speed|_rate|_period|_hz|timeconst|timestep)$")
TIMED_FLAGS = ("video_fps", "video_speed")


def numeric_flags() -> list[tuple[str, str, object]]:
    """(command, dest, type) of every flag that takes a number."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for command, p in sub.choices.items():
        for action in p._actions:
            if action.type in (int, float, seed_arg):
                out.append((command, action.dest, action.type))
    return out


def numeric_keys() -> list[tuple[str, object]]:
    """(key, value) of every count, rate, speed and time of the configuration."""
    out = []
    for s in settings(profile("smoke")):
        if isinstance(s.value, bool) or s.key in SEED_FIELDS:
            continue
        if isinstance(s.value, int) or (isinstance(s.value, float) and TIMED.search(s.key)):
            out.append((s.key, s.value))
    return out


def test_the_collections_are_not_empty() -> None:
    assert len(numeric_flags()) > 20 and len(numeric_keys()) > 25
    assert {"assembly.settle_time", "assembly.hop_speed", "agent.learning_rate",
            "assembly.max_retries", "reproduce.sweep_offsets"} <= {k for k, _ in numeric_keys()}


@pytest.mark.parametrize(("command", "dest", "kind"), numeric_flags())
def test_every_numeric_flag_has_a_ceiling(command: str, dest: str, kind: object) -> None:
    assert dest in FLAG_BOUNDS or dest in OVERRIDE_FLAGS, f"vgs {command} --{dest}: no bound"
    values = [HUGE_COUNT, -1] if kind is not float else [HUGE, -HUGE, TINY, float("nan")]
    for value in values:
        low, high = FLAG_BOUNDS[dest][:2] if dest in FLAG_BOUNDS else BOUNDS[OVERRIDE_FLAGS[dest]]
        args = argparse.Namespace(**{dest: value})
        if low <= value <= high and not (dest in TIMED_FLAGS and value == TINY):
            check_flag_bounds(args)  # a seed of 10**9 is a seed, an offset of 1e-12 mm one
            continue
        with pytest.raises(ConfigError) as info:
            check_flag_bounds(args)
        assert info.value.field == f"--{dest.replace('_', '-')}"
        assert bound_text(low, high) in info.value.message


@pytest.mark.parametrize(("key", "value"), numeric_keys())
def test_every_count_rate_speed_and_time_key_has_a_ceiling(key: str, value: object) -> None:
    assert key in BOUNDS, f"{key}: no bound in vgs.validate.BOUNDS"
    low, high = BOUNDS[key]
    tries = [HUGE_COUNT] if isinstance(value, int) else [HUGE, TINY]
    for tried in tries:
        argv = ["export-scene", "--profile", "smoke", "--set", f"{key}={tried!r}"]
        if low <= tried <= high:
            assert tried == TINY and not key.endswith("_speed")  # a time of 1e-12 s is none
            config_from_args(build_parser().parse_args(argv))
            continue
        with pytest.raises(ConfigError) as info:
            config_from_args(build_parser().parse_args(argv))
        assert info.value.field == key and bound_text(low, high) in info.value.message


def test_the_longest_time_is_the_longest_phase_time_out() -> None:
    from vgs.config.control import MAX_PHASE_TIMEOUT_S

    assert MAX_TIME_S == MAX_PHASE_TIMEOUT_S
    for phase in ("transport", "search"):
        timeouts = dict(profile("smoke").assembly.timeouts)
        timeouts[phase] = HUGE
        with pytest.raises(ConfigError, match="3600"):
            config_from_args(build_parser().parse_args(
                ["export-scene", "--set", f"assembly.timeouts={tuple(timeouts.items())!r}"]))


@pytest.mark.parametrize(("key", "value", "phase"), [
    ("assembly.settle_time", 100.0, "transport"),
    ("assembly.settle_time", 10.5, "transport"),  # twice 10.5 s against 20 s
    ("assembly.hop_press_time", 200.0, "search"),
    ("assembly.still_time", 31.0, "slide"),
    ("assembly.wiggle_period", 61.0, "align"),
])
def test_no_phase_waits_longer_than_its_time_out(key: str, value: float, phase: str) -> None:
    with pytest.raises(ConfigError) as info:
        config_from_args(build_parser().parse_args(["export-scene", "--set", f"{key}={value}"]))
    assert info.value.field == key and f"the {phase} phase waits" in info.value.message
    assert set(PHASE_WAITS) == {name for name, _ in profile("smoke").assembly.timeouts}


def test_waits_within_the_time_outs_pass() -> None:
    cfg = config_from_args(build_parser().parse_args(
        ["export-scene", "--set", "assembly.settle_time=9.5", "--set",
         "assembly.timeouts=(('transport', 19.0), ('approach', 19.0), ('search', 1.0), "
         "('slide', 1.0), ('align', 3.0), ('insert', 3.0))"]))
    assert cfg.assembly.settle_time == 9.5


@pytest.mark.parametrize("text", [
    "-" * 100_000 + "1", "not " * 2000 + "1", "~" * 5000 + "1", "(" * 3000 + ")" * 3000,
    "[" * 40 + "]" * 40, "-" * 33 + "1", "1" * 5000,
])
def test_set_literals_are_bounded_before_they_are_parsed(text: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_value(text, "seed")
    assert info.value.field == "seed" and ("4096" in info.value.message
                                           or "32 deep" in info.value.message)


def test_literals_within_the_bounds_parse() -> None:
    assert parse_value("-" * 31 + "1") == "-" * 31 + "1"  # not a literal: text
    assert parse_value("'" + "-" * 100 + "'") == "-" * 100  # quoted text nests nothing
    assert parse_value("((1, 2), (3, (4, 5)))") == ((1, 2), (3, (4, 5)))


def one_line(capsys: pytest.CaptureFixture[str], code: int) -> str:
    captured = capsys.readouterr()
    assert code == 2 and captured.err.count("\n") == 1 and "Traceback" not in captured.err
    return captured.err


@pytest.mark.parametrize(("argv", "needle"), [
    (["sweep", "--offsets", str(HUGE_COUNT), "--trials", "1"], "--offsets: must lie in [1, 1000]"),
    (["evaluate", "--policy", "center", "--episodes", "1", "--videos", "3"],
     "--videos: must lie in [0, 1]"),
    (["evaluate", "--policy", "center", "--episodes", "1", "--videos", str(HUGE_COUNT)],
     "--videos: must lie in [0, 1000000]"),
    (["demo", "--video-speed", "1e-12", "--video", "x.gif"], "--video-speed: must lie in"),
    (["demo", "--video-fps", "1e12", "--video", "x.gif"], "--video-fps: must lie in"),
    (["demo", "--peg-mass", "1e308"], "--peg-mass: must lie in [0.001, 50]"),
    (["demo", "--set", "seed=" + "-" * 100_000], "seed: the value is 100000 characters"),
    (["demo", "--set", "seed=" + "not " * 1000 + "1"], "seed: the value nests"),
    (["train", "--mode", "vgs", "--profile", "smoke", "--set", "assembly.settle_time=1e9"],
     "assembly.settle_time: must lie in [0, 3600]"),
    (["train", "--mode", "vgs", "--set", "seed=1", "--set", "seed=2"], "seed: is given twice"),
])
def test_the_refusals_are_one_line_and_write_nothing(
        argv: list[str], needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    err = one_line(capsys, main([*argv, "--out", str(out)]))
    assert needle in err
    assert not out.exists()
