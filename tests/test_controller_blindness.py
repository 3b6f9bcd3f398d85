"""The controller decides from its sensors and the nominal product data only.

Two checks (issue 55, item 3): the controller's modules name no ground truth (a static scan of
their source for the simulator's true peg and hole, the contact list and the constraint
forces), and during whole episodes nothing in those modules calls the cell's ground-truth
accessors (``Cell.peg_pose``, ``Cell.hole_position``); the assembly module is handed the
nominal peg even when the episode's peg differs.
"""

from __future__ import annotations

import ast
import inspect
from dataclasses import replace
from pathlib import Path

import pytest

import vgs
from vgs.assembly import strategy
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.config import profile
from vgs.sim.cell import Cell

SRC = Path(vgs.__file__).parent
CONTROLLER = [SRC / "control", SRC / "assembly" / "strategy.py", SRC / "assembly" / "contact.py",
              SRC / "assembly" / "spiral.py"]
# Names that reach the simulator's truth about the peg, the hole and the contacts.
FORBIDDEN = {"peg_pose", "hole_position", "hole_xy", "peg_body", "peg_geom", "peg_qpos",
             "peg_dof", "contact", "efc_force", "efc_id", "xpos", "xquat", "com_shift_mm",
             "mocap_pos", "stiction"}


# (file, name) pairs that name the truth for the record, never for a decision.
RECORD_ONLY = {("robot.py", "peg_pose")}  # Trace: the peg's lower end for figures


def _controller_files() -> list[Path]:
    return sorted(p for root in CONTROLLER
                  for p in ([root] if root.is_file() else root.rglob("*.py")))


def test_the_controller_names_no_ground_truth() -> None:
    found = []
    for path in _controller_files():
        for node in ast.walk(ast.parse(path.read_text())):
            name = (node.attr if isinstance(node, ast.Attribute)
                    else node.id if isinstance(node, ast.Name) else None)
            if name in FORBIDDEN and (path.name, name) not in RECORD_ONLY:
                found.append(f"{path.relative_to(SRC)}:{node.lineno} {name}")
    assert found == []


def _called_from_controller() -> str | None:
    controller = {str(p) for p in _controller_files()}
    for frame in inspect.stack()[2:]:
        if frame.filename in controller:
            return f"{Path(frame.filename).name}:{frame.lineno} {frame.function}"
    return None


@pytest.mark.parametrize("offset", [0.0, 0.03])
def test_no_ground_truth_reaches_the_controller_during_an_episode(
        offset: float, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[str] = []
    for name in ("peg_pose", "hole_position"):
        original = getattr(Cell, name)

        def spy(self, _original=original, _name=name):  # noqa: ANN001, ANN202
            where = _called_from_controller()
            if where:
                calls.append(f"{_name} from {where}")
            return _original(self)

        monkeypatch.setattr(Cell, name, spy)
    handed = []
    init = strategy.AssemblyModule.__init__

    def record_peg(self, robot, cfg, nominal_peg, *args, **kwargs):  # noqa: ANN001, ANN202
        handed.append(nominal_peg)
        init(self, robot, cfg, nominal_peg, *args, **kwargs)

    monkeypatch.setattr(strategy.AssemblyModule, "__init__", record_peg)
    cfg = profile("paper")
    heavy = replace(cfg.cell.peg, mass=cfg.cell.peg.mass * 1.15)
    record, _, _ = EpisodeRunner(cfg).run(3, offset_policy(offset), peg=heavy)
    assert record.grasp_success
    assert calls == []
    assert handed == [cfg.cell.peg]  # the drawing's peg, not the episode's heavier one
