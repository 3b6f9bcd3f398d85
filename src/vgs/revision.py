"""The source revision vgs runs from, whatever the install.

- Imported from a git checkout (an editable install or ``PYTHONPATH=src``): the checkout's live
  ``HEAD``, with ``+modified`` when files under ``src/`` differ from it.
- Installed from a wheel (or any build of ``build_py``): the revision the build recorded in the
  package file :data:`BUILD_INFO` (``setup.py`` writes it with :func:`checkout_revision` of the
  tree it builds; ``"unknown"`` when that tree is not a git checkout).
- A copy of the package without that file: ``"installed package"``.

This module imports nothing of vgs, so that ``setup.py`` can load it by its path at build time.
"""

from __future__ import annotations

import functools
import json
import subprocess
from pathlib import Path

BUILD_INFO = "build_info.json"
"""The file, inside the installed package ``vgs/``, that holds ``{"source_revision": ...}``."""

INSTALLED = "installed package"
"""The source revision of a copy that is neither a checkout nor a recorded build."""

PACKAGE = Path(__file__).resolve().parent


def checkout_revision(root: Path) -> str | None:
    """``git rev-parse HEAD`` of the git work tree whose top folder is ``root``, with
    ``+modified`` when files under ``root/src`` differ from it; None if ``root`` is not the top of
    a work tree (a folder inside another repository included), ``"unknown"`` if git fails."""
    def git(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(["git", *args], capture_output=True, text=True, cwd=root,
                              timeout=10)

    try:
        top = git("rev-parse", "--show-toplevel").stdout.strip()
        if not top or Path(top).resolve() != root.resolve():
            return None
        rev = git("rev-parse", "HEAD").stdout.strip()
        if not rev:
            return "unknown"
        dirty = git("diff", "--quiet", "HEAD", "--", "src").returncode == 1
        return rev + ("+modified" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


@functools.cache
def source_revision() -> str:
    """The revision of the vgs being run (module docstring): a commit (``+modified``), or
    ``"unknown"`` (a checkout without a usable git, a build outside git), or
    ``"installed package"`` (a copy without a build record)."""
    src = PACKAGE.parent
    root = src.parent
    if src.name == "src" and (root / "pyproject.toml").is_file():
        live = checkout_revision(root)
        if live is not None:
            return live
    return built_revision(PACKAGE) or INSTALLED


def built_revision(package: Path) -> str | None:
    """The revision a build recorded in ``package/build_info.json``; None without the file."""
    try:
        recorded = json.loads((package / BUILD_INFO).read_text()).get("source_revision")
    except (OSError, ValueError, AttributeError):
        return None
    return str(recorded) if recorded else None


def short_revision(revision: object) -> str:
    """A revision as a header shows it: a commit to its first 10 hex digits (``+modified``
    kept), any other text (``installed package``, ``unknown``) whole; ``?`` for none."""
    text = str(revision) if revision else "?"
    commit, plus, rest = text.partition("+")
    if len(commit) >= 10 and all(c in "0123456789abcdef" for c in commit):
        return commit[:10] + plus + rest
    return text
