"""Configuration: profiles validate, overrides validate, bad values name their field."""

from __future__ import annotations

import json

import pytest

from vgs.config import PROFILES, ExperimentConfig, from_dict, override, profile, to_dict
from vgs.errors import ConfigError, VGSError


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_profile_validates_and_round_trips(name: str) -> None:
    cfg = profile(name)
    assert isinstance(cfg, ExperimentConfig)
    assert cfg.name == name
    json.dumps(to_dict(cfg))  # plain JSON
    assert from_dict(ExperimentConfig, to_dict(cfg)) == cfg


def test_cell_is_the_same_in_all_profiles() -> None:
    cells = {name: profile(name).cell for name in PROFILES}
    assert len(set(cells.values())) == 1


def test_unknown_profile() -> None:
    with pytest.raises(ConfigError) as info:
        profile("huge")
    assert info.value.field == "profile"


@pytest.mark.parametrize(
    ("path", "value"),
    [("cell.peg.mass", 0.6), ("cell.peg.length", 0.12), ("cell.hole.clearance", 0.0005),
     ("cell.gripper.force", 20.0), ("assembly.search_tilt_deg", 4.0), ("seed", 5)],
)
def test_override_returns_a_validated_copy(path: str, value: float) -> None:
    cfg = profile("paper")
    new = override(cfg, path, value)
    node = new
    for part in path.split("."):
        node = getattr(node, part)
    assert node == value
    assert new != cfg and cfg == profile("paper")


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("cell.peg.mass", -0.1, "peg.mass"),
        ("cell.peg.mass", float("nan"), "peg.mass"),
        ("cell.peg.length", 0.03, "peg.length"),
        ("cell.peg.diameter", 0.0, "peg.diameter"),
        ("cell.hole.clearance", 0.0, "hole.clearance"),
        ("cell.hole.clearance", -0.001, "hole.clearance"),
        ("cell.hole.segments", 4, "hole.segments"),
        ("cell.hole.depth", 0.2, "hole.depth"),
        ("cell.gripper.force", 50.0, "gripper.force"),
        ("cell.gripper.force", 2.0, "gripper.force"),
        ("cell.sim.contact_timeconst", 0.001, "sim.contact_timeconst"),
        ("cell.camera.size", 8, "camera.size"),
        ("controller.joint_kp", (1.0, 2.0), "controller.joint_kp"),
        ("assembly.insertion_depth", 0.0, "assembly.insertion_depth"),
        ("network.backbone", "resnet", "network.backbone"),
        ("agent.momentum", 1.5, "agent.momentum"),
        ("train.device", "tpu", "train.device"),
        ("eval.mass_range", 2.0, "eval.mass_range"),
    ],
)
def test_bad_values_name_their_field(path: str, value: object, field: str) -> None:
    with pytest.raises(ConfigError) as info:
        override(profile("paper"), path, value)
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: ")
    assert isinstance(info.value, VGSError)


def test_unknown_field_is_named() -> None:
    with pytest.raises(ConfigError) as info:
        override(profile("paper"), "cell.peg.colour", 1)
    assert info.value.field == "cell.peg.colour"  # the whole path, not its last part
