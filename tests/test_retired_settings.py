"""Settings vgs removed because they could change no result (``agent.gamma``,
``agent.target_update_period``: every grasp is a terminal one-step episode, y = R) are ignored
in configurations recorded before: their run folders stay resumable."""

from __future__ import annotations

from pathlib import Path

import pytest

from vgs.config import AgentConfig, profile, same_config, to_dict, without_retired
from vgs.errors import RunMismatchError
from vgs.runfolder.common import check_request
from vgs.validate import BOUNDS


def _recorded_before() -> dict:
    saved = to_dict(profile("smoke"))
    saved["agent"].update(gamma=0.5, target_update_period=2)
    return saved


def test_the_fields_are_gone() -> None:
    assert not {"gamma", "target_update_period"} & set(to_dict(AgentConfig()))
    assert AgentConfig.RETIRED == ("gamma", "target_update_period")


def test_a_configuration_recorded_with_them_is_the_same_configuration(tmp_path: Path) -> None:
    saved, cfg = _recorded_before(), profile("smoke")
    assert without_retired(type(cfg), saved) == to_dict(cfg)
    assert same_config(saved, cfg)
    assert check_request(saved, cfg, tmp_path / "run.json") == []


def test_other_unknown_fields_are_still_refused(tmp_path: Path) -> None:
    saved = _recorded_before()
    saved["agent"]["no_such_setting"] = 1
    with pytest.raises(RunMismatchError, match="agent.no_such_setting"):
        check_request(saved, profile("smoke"), tmp_path / "run.json")


def test_every_bound_names_a_field() -> None:
    cfg = profile("paper")
    for path in BOUNDS:
        value = cfg
        for name in path.split("."):
            assert hasattr(value, name), path
            value = getattr(value, name)
