"""The configuration from the command line: the profile, the cell flags and ``--set``
checked, and the argparse types of the flags."""

from __future__ import annotations

import argparse
import ast
import os
from dataclasses import is_dataclass
from pathlib import Path
from typing import Any, NoReturn

from vgs.config import (
    NO_SUCH_FIELD,
    ExperimentConfig,
    PegConfig,
    override,
    profile,
    read_config_file,
)
from vgs.errors import ConfigError, VGSError
from vgs.runfolder.folderkind import MARKERS
from vgs.validate import check_config

# Flag -> dotted configuration path. Values are SI (m, kg, N).
OVERRIDE_FLAGS: dict[str, str] = {
    "peg_mass": "cell.peg.mass",
    "peg_length": "cell.peg.length",
    "peg_diameter": "cell.peg.diameter",
    "clearance": "cell.hole.clearance",
    "hole_depth": "cell.hole.depth",
    "gripper_force": "cell.gripper.force",
}


class UsageError(VGSError):
    """Command-line input that argparse rejects."""


class CommandParser(argparse.ArgumentParser):
    """An argument parser that raises instead of printing usage and exiting."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


def parse_value(text: str) -> Any:
    """A Python literal if ``text`` is one, else the text itself."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def _current(cfg: Any, path: str) -> Any:
    """The value at the dotted ``path`` of ``cfg``, or None if there is none."""
    for name in path.split("."):
        cfg = getattr(cfg, name, None)
    return cfg


def apply_override(cfg: ExperimentConfig, path: str, value: Any) -> ExperimentConfig:
    """``override(cfg, path, value)`` with every bad value reported as a ConfigError.

    A tuple field given text that is not a Python literal takes its comma-separated items, so
    ``reproduce.conditions=nominal,mass`` and ``reproduce.conditions=(nominal,)`` both work.
    """
    if is_dataclass(_current(cfg, path)):  # a section such as cell.peg: only its keys are set
        raise ConfigError(path, "is a group of keys, not one key (vgs config lists them)")
    if isinstance(value, str) and isinstance(_current(cfg, path), tuple):
        items = value.strip().strip("()[]").split(",")
        value = tuple(parse_value(item.strip()) for item in items if item.strip())
    try:
        return override(cfg, path, value)
    except ConfigError as exc:
        if exc.message == NO_SUCH_FIELD:
            raise ConfigError(exc.field, f"{NO_SUCH_FIELD} (vgs config lists them)") from None
        raise
    except (TypeError, ValueError) as exc:
        raise ConfigError(path, f"invalid value {value!r} ({exc})") from exc


def check_hole_fits(cfg: ExperimentConfig) -> None:
    """The hole (made for the nominal peg plus the clearance) must be wider than the peg, and
    deeper than the insertion depth K.

    Raises:
        ConfigError: ``hole.clearance`` or ``hole.depth`` otherwise.
    """
    hole, peg = cfg.cell.hole, cfg.cell.peg
    depth_k = cfg.assembly.insertion_depth
    if hole.depth <= depth_k:
        raise ConfigError("hole.depth", f"{hole.depth * 1000:g} mm must exceed the insertion "
                                        f"depth K = {depth_k * 1000:g} mm")
    if hole.diameter <= peg.diameter:
        raise ConfigError(
            "hole.clearance",
            f"the hole ({hole.diameter * 1000:g} mm = {hole.peg_diameter * 1000:g} mm + "
            f"{hole.clearance * 1000:g} mm clearance) must be wider than the peg "
            f"({peg.diameter * 1000:g} mm)",
        )


def config_from_args(args: argparse.Namespace) -> ExperimentConfig:
    """The profile (or the ``--config`` file) with the override flags and ``--set`` pairs
    applied, checked.

    A command that reads only some sections of the configuration (``args.config_sections``,
    e.g. ``model-info``: ``network``) refuses ``--set`` keys outside them.
    """
    cfg = base_config(args)
    # The hole is made for the nominal peg: --peg-diameter changes the peg, not the hole.
    cfg = apply_override(cfg, "cell.hole.peg_diameter", PegConfig().diameter)
    for flag, path in OVERRIDE_FLAGS.items():
        value = getattr(args, flag, None)  # commands without the cell flags have none
        if value is not None:
            cfg = apply_override(cfg, path, value)
    sections = getattr(args, "config_sections", None)
    for pair in args.set:
        key, sep, text = pair.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError("set", f"expected key=value, got {pair!r}")
        if sections and key.split(".")[0] not in sections:
            raise ConfigError("set", f"vgs {args.command} uses only the keys "
                                     f"{', '.join(f'{name}.*' for name in sections)}, not {key}")
        cfg = apply_override(cfg, key, parse_value(text.strip()))
    cfg = check_config(cfg)  # types (True is not a mass) and seeds
    check_hole_fits(cfg)
    return cfg


def base_config(args: argparse.Namespace) -> ExperimentConfig:
    """The configuration before any flag: ``--config FILE`` (a run folder: its metadata file),
    else the ``--profile`` (default ``paper``).

    Raises:
        ConfigError: ``config`` if both are given (each names a whole configuration), or the
            file's errors (:func:`vgs.config.read_config_file`).
    """
    source = getattr(args, "config", None)
    if source is None:
        return profile(args.profile or "paper")
    if args.profile is not None:
        raise ConfigError("config", "--config and --profile each name a whole configuration; "
                                    "give one (change single keys with --set)")
    path = Path(source)
    if path.is_dir():
        found = [path / name for name in MARKERS if (path / name).is_file()]
        if not found:
            raise ConfigError("config", f"{path}: is a folder without a run's metadata "
                                        f"({', '.join(MARKERS)}); name a file")
        path = found[0]
    return read_config_file(path)


def config_label(args: argparse.Namespace) -> str:
    """Where the configuration came from, for a header: ``profile P`` or ``config FILE``."""
    source = getattr(args, "config", None)
    return f"profile {args.profile or 'paper'}" if source is None else f"config {source}"


def flag_overrides(cfg: ExperimentConfig, args: argparse.Namespace,
                   fields: dict[str, str]) -> ExperimentConfig:
    """Apply the command's own flags (``{flag name: dotted config path}``) that were given."""
    for flag, path in fields.items():
        value = getattr(args, flag)
        if value is not None:
            cfg = apply_override(cfg, path, value)
    return cfg


def seed_arg(text: str) -> int:
    """An argparse type: a seed is a non-negative integer."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a seed must be a non-negative integer, got "
                                         f"{text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"a seed must be a non-negative integer, got {value}")
    return value


def parse_offsets_mm(text: str) -> tuple[float, ...]:
    """Comma-separated millimetres -> metres."""
    try:
        values = tuple(float(v) / 1000.0 for v in text.split(",") if v.strip())
    except ValueError as exc:
        raise ConfigError("offsets", f"expected comma-separated numbers in mm, got {text!r}") \
            from exc
    if not values:
        raise ConfigError("offsets", "no offsets given")
    return values


def check_video_name(name: str) -> None:
    """Raise :class:`ConfigError` (``video``) unless ``name`` ends in .mp4 or .gif."""
    if Path(name).suffix.lower() not in (".mp4", ".gif"):
        raise ConfigError("video", f"{name}: the file must end in .mp4 or .gif")


def headless_gl_default() -> None:
    """Let MuJoCo render headless (``MUJOCO_GL=egl``) where no display is set and the user
    chose no back end; must run before mujoco is first imported to take effect."""
    if "MUJOCO_GL" not in os.environ and not (os.environ.get("DISPLAY")
                                              or os.environ.get("WAYLAND_DISPLAY")):
        os.environ["MUJOCO_GL"] = "egl"


def parse_video_size(text: str) -> tuple[int, int]:
    """``WxH`` -> (width, height) in pixels."""
    w, sep, h = text.lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        size = (0, 0)
    if not sep or not (16 <= size[0] <= 1920 and 16 <= size[1] <= 1080):
        raise ConfigError("video-size", f"expected WxH within 16-1920 x 16-1080, got {text!r}")
    return size
