"""The import rules of docs/architecture.md ("Packages and what they may import"), held against
the code: every ``import vgs.X`` in src/vgs, at module level or inside a function."""

from __future__ import annotations

import ast
from pathlib import Path

import vgs

ROOT = Path(vgs.__file__).parent

# unit -> the units it may import (besides itself). A unit is a package folder ("sim") or a
# top-level module ("config"). Keep in step with the table in docs/architecture.md.
MAY_IMPORT: dict[str, set[str]] = {
    "errors": set(),
    "jsonsafe": set(),
    "configdoc": set(),
    "columns": set(),
    "perception": set(),
    "vecmath": set(),
    "native": set(),
    "config": {"errors"},
    "validate": {"errors"},
    "checkpoint": {"errors", "jsonsafe"},
    "sim": {"errors", "config", "vecmath", "native"},
    "grasping": {"errors", "config", "perception"},
    "control": {"errors", "config", "vecmath", "native", "sim"},
    "render": {"errors", "config", "sim"},
    "assembly": {"errors", "columns", "config", "perception", "vecmath", "native", "sim",
                 "control"},
    "revision": set(),
    "runfolder": {"errors", "jsonsafe", "columns", "config", "validate", "checkpoint",
                  "grasping", "revision"},
    "rollout": {"errors", "config", "validate", "checkpoint", "runfolder", "sim", "grasping",
                "assembly"},
    "analysis": {"errors", "columns", "config", "checkpoint", "runfolder", "grasping", "control",
                 "assembly", "rollout"},
    "experiments": {"errors", "jsonsafe", "columns", "config", "validate", "checkpoint",
                    "runfolder", "sim", "grasping", "assembly", "rollout", "analysis"},
    "tools": {"errors", "jsonsafe", "columns", "config", "checkpoint", "runfolder", "sim",
              "grasping", "control", "render", "assembly", "rollout"},
    "envs": {"errors", "config", "validate", "perception", "sim", "grasping", "render",
             "assembly", "rollout"},
    "cli": {"errors", "jsonsafe", "columns", "configdoc", "config", "perception", "validate",
            "revision", "checkpoint", "runfolder", "sim", "grasping", "control", "render",
            "assembly", "analysis", "experiments", "tools", "vgs"},
    "vgs": {"envs"},  # the package's face: __version__ and the environment's registration
}


# A compiled module belongs to the unit of its Python face (vgs._native, from _native.c).
COMPILED = {"_native": "native"}


def _unit(module: str) -> str:
    """``vgs.sim.cell`` -> ``sim``; ``vgs.config`` -> ``config``; ``vgs`` -> ``vgs``."""
    parts = module.split(".")
    return COMPILED.get(parts[1], parts[1]) if len(parts) > 1 else "vgs"


def _module_name(path: Path) -> str:
    parts = ("vgs", *path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """The vgs modules ``path`` imports (``from vgs import checkpoint`` is vgs.checkpoint)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "vgs"}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "vgs":
                found |= {f"vgs.{a.name}" if (ROOT / f"{a.name}.py").exists()
                          or (ROOT / f"{a.name}.c").exists() or (ROOT / a.name).is_dir()
                          else "vgs" for a in node.names}
            elif node.module.split(".")[0] == "vgs":
                found.add(node.module)
    return found


def test_every_unit_is_in_the_table() -> None:
    units = {_unit(_module_name(p)) for p in ROOT.rglob("*.py")}
    assert units == set(MAY_IMPORT)


def test_packages_import_only_what_the_architecture_allows() -> None:
    wrong = []
    for path in sorted(ROOT.rglob("*.py")):
        unit = _unit(_module_name(path))
        for module in sorted(_imports(path)):
            target = _unit(module)
            if target != unit and target not in MAY_IMPORT[unit]:
                wrong.append(f"{path.relative_to(ROOT)} imports {module}")
    assert wrong == []


# Modules that import each other (directly or round a loop), counting imports inside functions.
# None is left (docs/architecture.md); a new one fails here.
KNOWN_CYCLES: list[set[str]] = []


def test_no_new_import_cycle() -> None:
    modules = {_module_name(p): p for p in ROOT.rglob("*.py")}
    graph = {name: {m for m in _imports(path) if m in modules and m != name}
             for name, path in modules.items()}

    def reach(start: str) -> set[str]:
        seen, todo = set(), [start]
        while todo:
            for nxt in graph[todo.pop()] - seen:
                seen.add(nxt)
                todo.append(nxt)
        return seen

    reachable = {name: reach(name) for name in graph}
    cycles = []
    for name in sorted(graph):
        group = {name} | {m for m in reachable[name] if name in reachable[m]}
        if len(group) > 1 and group not in cycles:
            cycles.append(group)
    assert cycles == KNOWN_CYCLES

