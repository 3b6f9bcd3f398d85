"""A peg whose centre of mass is not its middle (issue 55): the compiled body's mass, centre
of mass and inertia against the configuration, the conditions that draw it, the record's
ground truth, and an episode on it."""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.config import condition_peg, eval_scenes, profile
from vgs.errors import ConfigError
from vgs.sim.cell import Cell
from vgs.sim.objects import peg_inertial


def _compiled(peg):  # noqa: ANN001, ANN202
    cfg = profile("paper")
    cell = Cell(replace(cfg.cell, peg=peg), cfg.controller.joint_kp, cfg.controller.joint_kv)
    return cell.model, cell.ids.peg_body


@pytest.mark.parametrize("shift_mm", [0.0, 10.0, 20.0, 30.0])
def test_the_compiled_peg_has_the_configured_mass_centre_and_inertia(shift_mm: float) -> None:
    nominal = profile("paper").cell.peg
    peg = replace(nominal, com_shift_mm=shift_mm, mass=0.6)
    m, body = _compiled(peg)
    assert m.body_mass[body] == pytest.approx(0.6, abs=1e-9)
    np.testing.assert_allclose(m.body_ipos[body], [0.0, 0.0, shift_mm / 1000.0], atol=1e-9)
    # The same body by hand: a uniform cylinder of the remaining mass plus an insert over the
    # last quarter (so the centre of mass lies at the shift), about the centre of mass.
    L, r, c = peg.length, peg.radius, shift_mm / 1000.0
    m_i = 0.6 * c / (3 * L / 8)
    m_b = 0.6 - m_i
    i_t = (m_b * ((3 * r * r + L * L) / 12 + c * c)
           + m_i * ((3 * r * r + (L / 4) ** 2) / 12 + (3 * L / 8 - c) ** 2))
    axial = 0.5 * 0.6 * r * r
    inertia = np.sort(m.body_inertia[body])
    np.testing.assert_allclose(inertia, np.sort([i_t, i_t, axial]), rtol=0, atol=1e-9)
    assert peg_inertial(peg)[2] == pytest.approx(i_t, abs=1e-12)
    if shift_mm == 0.0:  # the uniform peg: the geom's own mass, as before the option existed
        assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "peg_mark") == -1


def test_the_heavy_end_is_painted_only_when_visible() -> None:
    nominal = profile("paper").cell.peg
    for marking, present in (("visible", True), ("hidden", False)):
        m, _ = _compiled(replace(nominal, com_shift_mm=20.0, com_marking=marking))
        assert (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "peg_mark") >= 0) == present


@pytest.mark.parametrize("shift", [-1.0, 37.0, math.nan, True])
def test_an_impossible_shift_is_refused(shift: float) -> None:
    with pytest.raises(ConfigError, match="com_shift_mm"):
        replace(profile("paper").cell.peg, com_shift_mm=shift)


def test_the_conditions_draw_their_pegs() -> None:
    cfg = profile("paper")
    com = condition_peg(cfg.cell.peg, cfg.eval, "com", 0.3)
    hidden = condition_peg(cfg.cell.peg, cfg.eval, "com-hidden", 0.3)
    assert (com.com_shift_mm, com.com_marking) == (20.0, "visible")
    assert (hidden.com_shift_mm, hidden.com_marking) == (20.0, "hidden")
    spread = [s.peg.com_shift_mm for s in eval_scenes(cfg.cell.peg, cfg.eval, "com-spread", 7,
                                                      200)]
    assert 0.0 <= min(spread) < 2.0 and 18.0 < max(spread) <= 20.0
    # The same scenes (episode seeds) as the paper's conditions: paired comparisons.
    assert [s.seed for s in eval_scenes(cfg.cell.peg, cfg.eval, "com", 7, 5)] == \
        [s.seed for s in eval_scenes(cfg.cell.peg, cfg.eval, "nominal", 7, 5)]


def test_an_episode_on_a_shifted_peg_records_its_centre_of_mass() -> None:
    cfg = profile("paper")
    peg = replace(cfg.cell.peg, com_shift_mm=20.0)
    record, robot, _ = EpisodeRunner(cfg).run(3, offset_policy(0.0), peg=peg)
    assert record.grasp_success and record.peg_com_shift_mm == 20.0
    assert record.grasp_offset_com == pytest.approx(record.grasp_offset - 0.020, abs=1e-12)
    row = record.to_row()
    assert row["grasp_offset_com_mm"] == pytest.approx(row["grasp_offset_mm"] - 20.0)
    assert row["peg_com_shift_mm"] == 20.0 and row["across_mm"] >= 0.0


def test_the_com_oracle_grasps_at_the_true_centre_of_mass() -> None:
    from vgs.rollout.policies import Decision, episode_policy, load_policy

    cfg = profile("paper")
    peg = replace(cfg.cell.peg, com_shift_mm=20.0)
    oracle = load_policy("com-oracle", cfg)
    chosen: dict[str, Decision] = {}
    record, _, _ = EpisodeRunner(cfg).run(
        5, episode_policy(oracle, np.random.default_rng(0), chosen), peg=peg, assemble=False)
    assert record.grasp_success and chosen["decision"].command is not None
    # the pads close on the centre of mass (the grasp's settling moves them a little),
    # 20 mm from the middle towards the heavy end (body +z)
    assert abs(record.grasp_offset_com * 1000) < 2.0
    assert record.grasp_offset * 1000 == pytest.approx(20.0, abs=2.0)
    with pytest.raises(ConfigError, match="true centre of mass"):
        oracle(EpisodeRunner(cfg).observe(5, peg), np.random.default_rng(0))
