"""The assembly module's tunables are configuration fields: listed with their documentation,
validated, and absent from configurations recorded before they existed without changing what
those describe (their defaults are the values the module used as constants)."""

from __future__ import annotations

import pytest

from vgs.config import AssemblyConfig, override, profile, same_config, to_dict
from vgs.configdoc import settings
from vgs.errors import ConfigError

# The former module constants of vgs.assembly.contact (issue 40) and their values.
FORMER_CONSTANTS = {
    "rot_contact_damping": 2.5, "contact_damping": 300.0, "entry_depth": 0.004,
    "settle_time": 0.3, "length_tolerance": 0.15, "lost_width_fraction": 0.8,
    "retry_lift": 0.012, "rot_compliance_angle_deg": 2.0, "slide_settle_time": 0.3,
    "three_point_fraction": 0.5, "climb_travel": 0.003, "still_time": 0.3, "max_retries": 3,
    "align_step_deg": 3.0, "max_align_adjustments": 15, "max_insert_stalls": 4,
    "plane_contact_margin": 0.004, "plane_window": 5, "hop_height": 0.001,
    "hop_press_time": 0.15, "hop_lift_speed": 0.02, "hop_speed": 0.01,
    "hop_settle_time": 0.1, "hop_descent_speed": 0.003, "hop_rot_stiffness": 100.0,
}


def test_vgs_config_lists_every_former_constant_with_its_value_and_doc() -> None:
    listed = {s.key: s for s in settings(profile("paper"))}
    for name, value in FORMER_CONSTANTS.items():
        setting = listed[f"assembly.{name}"]
        assert setting.value == value and type(setting.value) is type(value)
        assert setting.doc, name


def test_a_configuration_recorded_without_the_fields_is_the_same_configuration() -> None:
    cfg = profile("smoke")
    saved = to_dict(cfg)
    for name in FORMER_CONSTANTS:
        del saved["assembly"][name]
    assert same_config(saved, cfg)
    assert not same_config(saved, override(cfg, "assembly.max_retries", 2))


@pytest.mark.parametrize(("name", "value"), [
    ("max_retries", -1), ("max_retries", 2.5), ("plane_window", 0), ("max_align_adjustments", 0),
    ("max_insert_stalls", True), ("lost_width_fraction", 1.5), ("three_point_fraction", -0.1),
    ("contact_damping", 0.0), ("rot_compliance_angle_deg", 0.0), ("hop_speed", -0.01),
    ("retry_lift", -0.001), ("still_time", float("nan")),
])
def test_bad_values_name_their_field(name: str, value: object) -> None:
    with pytest.raises(ConfigError, match=f"assembly.{name}"):
        AssemblyConfig(**{name: value})
