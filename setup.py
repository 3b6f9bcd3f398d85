"""The build hooks: the per-tick kernels in C, and the source revision recorded in a wheel (the
rest of the build is in pyproject.toml).

``vgs._native`` (``src/vgs/_native.c``) is compiled against the headers of the pinned MuJoCo
wheel (a build requirement, pyproject.toml) and linked to its ``libmujoco``; the flags keep every
double operation rounded once, in the written order (no fused multiply-add, no fast-math, libm
calls as CPython makes them), so that its ticks give the same bits as the Python floats they
replace on every x86-64 CPU (``src/vgs/native.py``).

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

from setuptools import Extension, setup
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


# Exact IEEE double arithmetic in the order written (see the module docstring).
EXACT_FLOATS = ["-O2", "-ffp-contract=off", "-fno-fast-math", "-fno-builtin", "-std=c11"]


def native_extension() -> Extension:
    """``vgs._native``, built against the installed (build-time) MuJoCo wheel."""
    import mujoco  # the build requirement pinned in pyproject.toml

    root = Path(mujoco.__file__).resolve().parent
    library = sorted(root.glob("libmujoco.so*"))
    if not library:
        raise RuntimeError(f"no libmujoco in {root}: vgs needs MuJoCo's Linux wheel to build")
    return Extension(
        "vgs._native",
        sources=["src/vgs/_native.c"],
        include_dirs=[str(root / "include")],
        extra_compile_args=EXACT_FLOATS,
        # Link to MuJoCo's library by its file name (its soname): vgs.native imports mujoco
        # first, so the loader finds it already loaded; the run path covers a plain install.
        library_dirs=[str(root)],
        libraries=[":" + library[0].name],
        runtime_library_dirs=["$ORIGIN/../mujoco"],
    )


setup(cmdclass={"build_py": BuildPyWithRevision}, ext_modules=[native_extension()])
