"""The build hook that records the source revision in a wheel (the rest of the build is in
pyproject.toml).

``build_py`` writes ``vgs/build_info.json`` (``{"source_revision": ...}``) into the build, never
into ``src/``: the commit of the checkout being built (``+modified`` when ``src/`` differs from
it), or ``"unknown"`` when the tree is not a git checkout (an unpacked sdist). An editable install
writes nothing: vgs then reads the checkout's live ``HEAD`` (``src/vgs/revision.py``, loaded here
by its path so that the build imports nothing of vgs's dependencies).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent


def _revision_module() -> ModuleType:
    """``src/vgs/revision.py``, loaded by its path (the package itself is not imported)."""
    spec = importlib.util.spec_from_file_location("_vgs_revision", ROOT / "src/vgs/revision.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BuildPyWithRevision(build_py):
    """``build_py`` that also writes ``vgs/build_info.json`` into the build folder."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        revision = _revision_module()
        source = revision.checkout_revision(ROOT) or "unknown"
        target = Path(self.build_lib) / "vgs" / revision.BUILD_INFO
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps({"source_revision": source}) + "\n")


setup(cmdclass={"build_py": BuildPyWithRevision})
