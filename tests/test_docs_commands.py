"""Every ``vgs ...`` command of README.md and docs/*.md parses with the CLI's own parser, as
written (nothing runs), so a command that names a missing flag, leaves out a required argument or
sets a key that does not exist fails here.

What is collected: each line of a fenced code block that starts with ``vgs `` (a ``\\``
continuation joined, ``&&`` and ``;`` chains split, ``# comments`` dropped), and each inline code
span that starts with ``vgs ``. Usage syntax is expanded: ``[...]`` optional parts are taken in,
``a|b`` alternatives (``a\\|b`` in a table) are each tried in turn, ``...`` repetitions dropped
and the placeholders of :data:`PLACEHOLDERS` filled in. A span without a positional argument that
omits a required flag (``vgs train --mode baseline`` in a sentence) is a reference to the command:
only its name, the flags it names and the values it gives are checked.
"""

from __future__ import annotations

import argparse
import re
import shlex
from pathlib import Path

import pytest

from vgs.cli import UsageError, build_parser, config_from_args

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^(```|~~~)[^\n]*\n(.*?)^\1", re.S | re.M)
SPAN = re.compile(r"(`+)(.+?)\1", re.S)

# Placeholders of the docs' usage lines -> a value the parser takes in their place.
PLACEHOLDERS = {
    "RUN": "runs/x", "RUN_DIR": "runs/x", "DIR": "runs/x", "DEST": "runs/y", "FOLDER": "runs/y",
    "FILE": "f.mp4", "N": "2", "S": "3", "MM": "10", "P": "quick", "C": "nominal",
    "ADDR": "auto", "NAME": "light", "KEY=VALUE": "seed=1", "COMMAND": "demo",
}


def collect(text: str) -> list[tuple[str, bool]]:
    """``(command, is_span)`` for each ``vgs`` command of the markdown ``text``."""
    found = []
    for match in FENCE.finditer(text):
        for line in match.group(2).replace("\\\n", " ").splitlines():
            for part in re.split(r"&&|;", line):
                part = re.sub(r"^\S*/(?=vgs )", "", part.strip())  # .venv/bin/vgs
                if part.startswith("vgs "):
                    found.append((part, False))
    for match in SPAN.finditer(FENCE.sub("", text)):
        code = " ".join(match.group(2).replace("\\|", "|").split())
        if code.startswith("vgs "):
            found.append((code, True))
    return found


def _variants(command: str) -> list[str]:
    """The usage line ``command`` with its ``[...]`` parts taken in and each ``a | b`` and
    ``a|b`` alternative tried once (the others at their first)."""
    group = re.search(r"\[([^\[\]]*)\]", command)
    if group:
        out = []
        for choice in group.group(1).split(" | "):
            out += _variants(command[:group.start()] + choice + command[group.end():])
        return out
    words = shlex.split(command, comments=True)
    firsts = [w.split("|")[0] if _alternatives(w) else w for w in words]
    out = [" ".join(shlex.quote(w) for w in firsts)]
    for i, word in enumerate(words):
        if _alternatives(word):
            for choice in word.split("|")[1:]:
                out.append(" ".join(shlex.quote(w) for w in [*firsts[:i], choice,
                                                             *firsts[i + 1:]]))
    return out


def _alternatives(word: str) -> bool:
    return "|" in word and not word.startswith("'")


def _argv(command: str) -> list[str]:
    """The arguments after ``vgs``: placeholders filled in, ``...`` repetitions dropped."""
    words = shlex.split(command, comments=True)[1:]
    argv: list[str] = []
    for word in words:
        if word == "..." and not (argv and argv[-1].startswith("--")):
            continue
        argv.append(PLACEHOLDERS.get(word, word))
    return argv


def _subparser(argv: list[str]) -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    if not argv or argv[0] not in sub.choices:
        raise UsageError(f"no command {argv[0] if argv else ''!r}")
    return sub.choices[argv[0]]


def check(command: str, is_span: bool) -> None:
    """Raise :class:`UsageError` (or a ConfigError) if ``command`` cannot work as written."""
    for variant in _variants(command):
        argv = _argv(variant)
        if argv in (["--help"], ["--version"]):  # the top-level options
            continue
        if "--help" in argv[1:]:
            _subparser(argv[:1])
            continue
        parser = _subparser(argv)
        options = {s for a in parser._actions for s in a.option_strings}
        unknown = [w for w in argv[1:] if w.startswith("--") and w.split("=")[0] not in options]
        if unknown:
            raise UsageError(f"vgs {argv[0]} takes no {unknown[0]}")
        positional = any(not w.startswith("-") and not argv[i - 1].startswith("--")
                         for i, w in enumerate(argv[1:], start=1))
        try:
            args, extra = build_parser().parse_known_args(argv)
        except UsageError as exc:
            if is_span and not positional and re.search(
                    r"arguments are required|expected one argument", str(exc)):
                continue  # a reference to the command in a sentence, not a command line
            raise
        if extra:
            raise UsageError(f"vgs {argv[0]} does not take {' '.join(extra)}")
        if hasattr(args, "profile") and getattr(args, "config", None) is None:
            config_from_args(args)  # the profile and every --set key exist


def _all() -> list[tuple[str, str, bool]]:
    return [(page.relative_to(ROOT).as_posix(), command, is_span)
            for page in PAGES for command, is_span in collect(page.read_text())]


def test_commands_are_found() -> None:
    found = _all()
    assert len(found) > 100
    assert ("README.md", "vgs reproduce --profile quick --out runs/quick", False) in found


@pytest.mark.parametrize(("page", "command", "is_span"), _all())
def test_every_docs_command_parses(page: str, command: str, is_span: bool) -> None:
    check(command, is_span)


@pytest.mark.parametrize(
    "line",
    [
        "`vgs heatmap RUN`",  # --out is required
        "`vgs curves RUN --no-such-flag`",
        "`vgs demo --seed S --no-such-flag`",
        "`vgs train --mode vgs --no-such-flag`",  # a reference naming a missing flag
        "`vgs evaluate --policy center --condition nominal\\|heavy --out DIR`",
        "`vgs no-such-command`",
        "`vgs --versions`",
        "```\nvgs reproduce --profile quick --out DIR --set train.no_such_key=1\n```",
        "```\nvgs export-scene \\\n  --peg-mass 0.6 --oops\n```",
        "```\nvgs reproduce --profile tiny --out DIR\n```",
    ],
)
def test_a_bad_line_fails(line: str) -> None:
    [(command, is_span)] = collect(f"A page.\n\n{line}\n")
    with pytest.raises((UsageError, ValueError)):
        check(command, is_span)


def test_usage_syntax_is_expanded() -> None:
    assert _variants("vgs demo [--offset MM | --policy RUN|random]") == [
        "vgs demo --offset MM", "vgs demo --policy RUN", "vgs demo --policy random"]
    assert _argv("vgs seeds DIR DIR ... --out DEST") == ["seeds", "runs/x", "runs/x", "--out",
                                                          "runs/y"]
    check("vgs report runs/x --title '...'", False)
