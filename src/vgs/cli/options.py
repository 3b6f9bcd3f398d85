"""The configuration from the command line: the profile, the cell flags and ``--set``
checked, and the argparse types of the flags."""

from __future__ import annotations

import argparse
import ast
import os
import re
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
from vgs.config.checks import shown
from vgs.errors import ConfigError, VGSError
from vgs.runfolder.folderkind import MARKERS
from vgs.validate import BOUNDS, MAX_EPISODES, MAX_SEED, bound_text, check_config

# Flag -> dotted configuration path. Values are SI (m, kg, N).
OVERRIDE_FLAGS: dict[str, str] = {
    "peg_mass": "cell.peg.mass",
    "peg_length": "cell.peg.length",
    "peg_diameter": "cell.peg.diameter",
    "clearance": "cell.hole.clearance",
    "hole_depth": "cell.hole.depth",
    "gripper_force": "cell.gripper.force",
}


# Every number a flag takes (argparse dest -> (lowest, highest), unit), checked before any work
# (the cell flags of OVERRIDE_FLAGS take the bound of their configuration key in BOUNDS).
FLAG_BOUNDS: dict[str, tuple[float, float, str]] = {
    "seed": (0, MAX_SEED, ""),
    "episodes": (1, MAX_EPISODES, ""),
    "workers": (1, BOUNDS["train.parallel_episodes"][1], ""),
    "offsets": (1, BOUNDS["reproduce.sweep_offsets"][1], ""),
    "trials": (1, BOUNDS["reproduce.sweep_trials"][1], ""),
    "mass_range": (0.0, 0.9, ""),
    "length_range": (0.0, 0.9, ""),
    "offset": (-250.0, 250.0, " mm"),
    "video_fps": (1.0, 60.0, " frames/s"),
    "video_speed": (0.1, 1000.0, " simulated s per s"),
    "videos": (0, MAX_EPISODES, ""),
    "traces": (0, MAX_EPISODES, ""),
    "rotations": (*BOUNDS["network.num_rotations"], ""),
    "size": (*BOUNDS["cell.camera.size"], " px"),
    "scenes": (1, 16, ""),
    "window": (1, MAX_EPISODES, " episodes"),
}


def check_flag_bounds(args: argparse.Namespace) -> None:
    """Every number given by a flag within its bound (:data:`FLAG_BOUNDS`, and :data:`BOUNDS`
    for the cell flags).

    Raises:
        ConfigError: ``--flag``, naming the bound.
    """
    for dest, value in sorted(vars(args).items()):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if dest in OVERRIDE_FLAGS:
            low, high, unit = (*BOUNDS[OVERRIDE_FLAGS[dest]], "")
        elif dest in FLAG_BOUNDS:
            low, high, unit = FLAG_BOUNDS[dest]
        else:
            continue
        if not low <= value <= high:
            raise ConfigError(f"--{dest.replace('_', '-')}",
                              f"must lie in {bound_text(low, high)}{unit}, got {shown(value)}")


class UsageError(VGSError):
    """Command-line input that argparse rejects."""


class CommandParser(argparse.ArgumentParser):
    """An argument parser that raises instead of printing usage and exiting."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


MAX_LITERAL_CHARS = 4096  # a --set value: the longest configuration value is ~200 characters
MAX_LITERAL_DEPTH = 32  # brackets and unary operators (-, +, ~, not) nested in a --set value


def literal_depth(text: str) -> int:
    """An upper bound of the nesting Python's parser recurses into for ``text``: the deepest
    brackets plus the longest chain of unary operators (``-``, ``+``, ``~``, ``not``), quoted
    text left out."""
    bare = _QUOTED.sub("''", text)
    depth = deepest = 0
    for char in bare:
        if char in "([{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in ")]}":
            depth = max(0, depth - 1)
    chains = [len(_UNARY_OP.findall(m.group())) for m in _UNARY_CHAIN.finditer(bare)]
    return deepest + max(chains, default=0)


_QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"")
_UNARY_OP = re.compile(r"[-+~]|\bnot\b")
_UNARY_CHAIN = re.compile(r"(?:(?:[-+~]|\bnot\b)\s*)+")


def parse_value(text: str, key: str = "set") -> Any:
    """A Python literal if ``text`` is one, else the text itself.

    The text is bounded before it is parsed (Python's parser recurses into nested brackets
    and unary operators, and a long literal can exhaust memory).

    Raises:
        ConfigError: ``key`` when the text is longer than :data:`MAX_LITERAL_CHARS` or nested
            deeper than :data:`MAX_LITERAL_DEPTH`.
    """
    if len(text) > MAX_LITERAL_CHARS:
        raise ConfigError(key, f"the value is {len(text)} characters long; at most "
                               f"{MAX_LITERAL_CHARS}")
    if literal_depth(text) > MAX_LITERAL_DEPTH:
        raise ConfigError(key, f"the value nests brackets or signs (-, +, ~, not) more than "
                               f"{MAX_LITERAL_DEPTH} deep")
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError):
        return text
    except (RecursionError, MemoryError):  # what the bounds above should already keep out
        raise ConfigError(key, "the value is too large or too deeply nested to parse") from None


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
    bound = BOUNDS.get(path)
    if bound is not None and isinstance(value, (int, float)) and not isinstance(value, bool) \
            and not bound[0] <= value <= bound[1]:  # named before the dataclass's own check
        raise ConfigError(path, f"must lie in {bound_text(*bound)}, got {shown(value)}")
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
    seen: set[str] = set()
    for pair in args.set:
        key, sep, text = pair.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError("set", f"expected key=value, got {shown(pair)}")
        if key in seen:
            raise ConfigError(key, "is given twice with --set; give each key once")
        seen.add(key)
        if sections and key.split(".")[0] not in sections:
            raise ConfigError("set", f"vgs {args.command} uses only the keys "
                                     f"{', '.join(f'{name}.*' for name in sections)}, not {key}")
        cfg = apply_override(cfg, key, parse_value(text.strip(), key))
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
    if len(values) > FLAG_BOUNDS["offsets"][1]:
        raise ConfigError("offsets-mm", f"{len(values)} offsets; at most "
                                        f"{FLAG_BOUNDS['offsets'][1]:g}")
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
