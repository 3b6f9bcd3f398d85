"""Golden records: the measuring instrument (cell, physics settings, controller) is unchanged.

Re-runs every case of ``tests/golden/cases.py`` and compares every field of every record, and a
digest of the final simulator state, exactly with ``tests/golden/records.json``. A failure here
means the physics or the controller changed: if that was meant, rewrite the file in the same
commit (``.venv/bin/python tests/golden/cases.py --write``), say so, and republish what depends
on the cell; if not, the change has a bug.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import mujoco
import pytest

sys.path.insert(0, str(Path(__file__).parent / "golden"))
from cases import CASES, RECORDS, run_case  # noqa: E402

from vgs.assembly.episode import EpisodeRunner  # noqa: E402
from vgs.config import profile  # noqa: E402

GOLDEN = json.loads(RECORDS.read_text())


@pytest.fixture(scope="module")
def runner() -> EpisodeRunner:
    """One runner for every case (its compiled cells are reused, as in a real run)."""
    return EpisodeRunner(profile("paper"))


def test_the_cases_cover_what_they_claim() -> None:
    records = GOLDEN["records"]
    assert {c.name for c in CASES} == set(records)
    reasons = {name: r["failure_reason"] for name, r in records.items()}
    assert reasons["center_success"] == reasons["plus35_success"] == ""
    assert reasons["minus35_success"] == reasons["varied_peg"] == ""
    assert reasons["grasp_miss"] == "grasp"
    assert reasons["plus45_timeout"].startswith("timeout:")
    assert abs(records["plus35_success"]["grasp_offset_mm"] - 35) < 3
    assert abs(records["minus35_success"]["grasp_offset_mm"] + 35) < 3


@pytest.mark.skipif(mujoco.__version__ != GOLDEN["mujoco_version"],
                    reason=f"golden records made with MuJoCo {GOLDEN['mujoco_version']}, "
                           f"installed {mujoco.__version__} (pyproject.toml pins it)")
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_golden_record_is_reproduced_exactly(case, runner: EpisodeRunner) -> None:
    got = run_case(runner, case)
    want = GOLDEN["records"][case.name]
    assert set(got) == set(want), "the record's fields changed"
    differ = {k: (want[k], got[k]) for k in want if got[k] != want[k]}
    assert not differ, f"{case.name}: fields differ (golden, now): {differ}"
