"""Type and seed checks of a whole configuration (vgs.validate) and the field-by-field
comparison of a request with a recorded configuration (vgs.runfolder.common.check_request)."""

from __future__ import annotations

from pathlib import Path

import pytest

from vgs.config import override, profile, to_dict
from vgs.errors import ConfigError, CorruptFileError, RunMismatchError
from vgs.runfolder.common import check_request
from vgs.validate import check_config, check_seed


@pytest.mark.parametrize(("path", "value", "field"), [
    ("cell.peg.mass", True, "cell.peg.mass"),
    ("cell.peg.mass", "heavy", "cell.peg.mass"),
    ("seed", "abc", "seed"),
    ("seed", 1.0, "seed"),
    ("seed", -1, "seed"),
    ("train.episodes", 2.5, "train.episodes"),
    ("train.episodes", False, "train.episodes"),
    ("cell.hole.randomize", 1, "cell.hole.randomize"),
    ("network.weights", 3, "network.weights"),
    ("controller.joint_kp", (1.0, "x", 1.0, 1.0, 1.0, 1.0), "controller.joint_kp[1]"),
    ("cell.hole.nominal_xy", (0.4,), "cell.hole.nominal_xy"),
    ("reproduce.train_seeds", (0, -2), "reproduce.train_seeds[1]"),
    ("reproduce.eval_seed", True, "reproduce.eval_seed"),
    ("agent.weight_decay", float("inf"), "agent.weight_decay"),  # (strict JSON has no inf)
    ("network.depth_mean", float("nan"), "network.depth_mean"),
    ("reward.threshold_s", float("inf"), "reward.threshold_s"),
])
def test_wrong_types_and_seeds_are_named(path: str, value, field: str) -> None:
    from vgs.cli import apply_override

    with pytest.raises(ConfigError) as info:  # by the dataclass's own check or by the types
        check_config(apply_override(profile("smoke"), path, value))
    assert info.value.field.split("[")[0] in (field.split("[")[0], path.split(".")[-1],
                                              ".".join(path.split(".")[-2:]))
    if info.value.field.startswith(path):
        assert info.value.field == field


def test_ints_of_float_fields_become_floats_and_good_values_pass() -> None:
    cfg = override(override(profile("smoke"), "cell.peg.mass", 1), "controller.joint_kp",
                   (6000, 6000, 4000, 1500, 1500, 1500))
    checked = check_config(cfg)
    assert type(checked.cell.peg.mass) is float
    assert all(type(v) is float for v in checked.controller.joint_kp)
    assert check_config(override(cfg, "network.weights", None)).network.weights is None
    assert check_config(profile("paper")) == profile("paper")
    assert check_seed("seed", 0) == 0
    with pytest.raises(ConfigError, match="non-negative"):
        check_seed("seed", -5)


def test_check_request_names_the_field_and_accepts_only_growth(tmp_path: Path) -> None:
    cfg = profile("smoke")
    saved = to_dict(cfg)
    where = tmp_path / "run.json"
    assert check_request(saved, cfg, where) == []
    more = override(cfg, "train.episodes", cfg.train.episodes + 5)
    assert check_request(saved, more, where, extendable=("train.episodes",)) == [
        "train.episodes"]
    with pytest.raises(RunMismatchError) as info:
        check_request(saved, more, where)
    assert info.value.field == "train.episodes"
    fewer = override(cfg, "train.episodes", 1)
    with pytest.raises(RunMismatchError, match="can only grow"):
        check_request(saved, fewer, where, extendable=("train.episodes",))
    with pytest.raises(RunMismatchError) as info:
        check_request(saved, override(cfg, "cell.peg.mass", 0.6), where)
    assert info.value.field == "cell.peg.mass"
    # fields added to vgs later take their defaults; fields vgs does not know are refused
    del saved["network"]["precision"]
    assert check_request(saved, cfg, where) == []
    saved["network"]["future_field"] = 1
    with pytest.raises(RunMismatchError) as info:
        check_request(saved, cfg, where)
    assert info.value.field == "network.future_field"
    with pytest.raises(CorruptFileError):
        check_request({"cell": {"peg": {"mass": -1.0}}}, cfg, where)
