"""The test conditions of the paper (4.2), the one registry: their names, their ranges, the peg
each draws, and the seeded test scenes every policy meets.

* ``nominal``: the configured peg (30 mm x 100 mm, 0.55 kg);
* ``mass``: ``m = m0 (1 + a u)`` with ``a = eval.mass_range`` (0.15);
* ``length``: ``L = L0 (1 + b u)`` with ``b = eval.length_range`` (0.15) and the mass following
  the volume, ``m = m0 L / L0``;

with ``u`` uniform in [-1, 1]; and a family whose centre of mass is not the middle (the
paper's reason for learning the grasp, 2.2), the heavy end's direction random per scene with
the peg's random yaw:

* ``com``: the peg's centre of mass ``eval.com_shift_mm`` (20 mm) from its middle, its heavy
  end painted (``peg.com_marking = visible``);
* ``com-hidden``: the same, unmarked;
* ``com-spread``: a manufacturing spread, the shift ``eval.com_spread_mm * |u|`` (so along
  any fixed direction of the peg uniform within +-20 mm), unmarked.

``vgs reproduce`` runs the paper's three (:data:`PAPER_CONDITIONS`) unless told otherwise.
Test scene ``i`` of root seed ``S`` is fully determined by
``(S, i)``: its episode seed (peg pose, hole displacement, sensor noise) is the first word of
``numpy.random.SeedSequence([S, i, EVAL_STREAM])`` (the tag keeps test scenes apart from the
training scenes ``SeedSequence([S, i])`` of a run with the same root seed), and a child of that
sequence draws ``u``. Two policies evaluated with the same seed meet the same scenes (a paired
comparison). Used by the evaluation (``vgs evaluate``, ``vgs reproduce``), its videos and the
Gymnasium environment; the report titles the conditions
(:data:`vgs.analysis.reportfigures.CONDITION_TITLES`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from vgs.config.cell import PegConfig
from vgs.config.checks import check_fraction
from vgs.errors import ConfigError

PAPER_CONDITIONS = ("nominal", "mass", "length")
COM_CONDITIONS = ("com", "com-hidden", "com-spread")
CONDITIONS = PAPER_CONDITIONS + COM_CONDITIONS
EVAL_STREAM = 0xE7A1  # tags the seed sequences of test episodes


@dataclass(frozen=True)
class EvalConfig:
    """Evaluation: the test episodes of one policy on one condition (paper 4.2).

    Attributes:
        episodes: Test episodes per policy and condition (paper: 1000).
        mass_range: The ``mass`` condition's peg mass factor is uniform in 1 +- this.
        length_range: The ``length`` condition's peg length factor is uniform in 1 +- this; the
            mass follows the length.
        com_shift_mm: The ``com`` and ``com-hidden`` conditions' centre of mass, from the
            peg's middle along its axis [mm].
        com_spread_mm: The ``com-spread`` condition's largest shift [mm] (``|u|`` of it).
    """

    episodes: int = 1000
    mass_range: float = 0.15
    length_range: float = 0.15
    com_shift_mm: float = 20.0
    com_spread_mm: float = 20.0

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise ConfigError("eval.episodes", "must be >= 1")
        check_fraction(self, "mass_range", "length_range", prefix="eval.")
        for name in ("com_shift_mm", "com_spread_mm"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not 0.0 <= value <= 36.0:
                raise ConfigError(f"eval.{name}", f"must lie in [0, 36] mm, got {value!r}")


@dataclass(frozen=True)
class EvalScene:
    """One test episode's scene.

    Attributes:
        index: Its index in the evaluation (0, 1, ...).
        seed: The episode seed (peg pose, hole displacement, sensor noise).
        peg: The peg of the condition drawn for it.
    """

    index: int
    seed: int
    peg: PegConfig


def condition_peg(nominal: PegConfig, evaluation: EvalConfig, condition: str,
                  factor: float) -> PegConfig:
    """The peg of a test condition for a draw ``factor`` (``u``) in [-1, 1].

    ``nominal``: ``nominal``; ``mass``: its mass times ``1 + evaluation.mass_range * u``;
    ``length``: its length times ``1 + evaluation.length_range * u``, the mass following;
    ``com``, ``com-hidden``, ``com-spread``: its centre of mass shifted (module docstring).

    Raises:
        ConfigError: ``condition`` if it is not one of :data:`CONDITIONS`.
    """
    if condition == "nominal":
        return nominal
    if condition == "mass":
        return replace(nominal, mass=nominal.mass * (1.0 + evaluation.mass_range * factor))
    if condition == "length":
        scale = 1.0 + evaluation.length_range * factor
        return replace(nominal, length=nominal.length * scale, mass=nominal.mass * scale)
    if condition == "com":
        return replace(nominal, com_shift_mm=evaluation.com_shift_mm, com_marking="visible")
    if condition == "com-hidden":
        return replace(nominal, com_shift_mm=evaluation.com_shift_mm, com_marking="hidden")
    if condition == "com-spread":
        return replace(nominal, com_shift_mm=evaluation.com_spread_mm * abs(factor),
                       com_marking="hidden")
    raise ConfigError("condition", f"must be one of {CONDITIONS}, got {condition!r}")


def eval_scenes(nominal: PegConfig, evaluation: EvalConfig, condition: str, seed: int,
                count: int) -> list[EvalScene]:
    """The first ``count`` test scenes of ``condition`` under root seed ``seed``, in index
    order (module docstring)."""
    scenes = []
    for i in range(count):
        seq = np.random.SeedSequence([seed, i, EVAL_STREAM])
        episode_seed = int(seq.generate_state(1)[0])
        rng = np.random.default_rng(seq.spawn(1)[0])
        peg = condition_peg(nominal, evaluation, condition, float(rng.uniform(-1.0, 1.0)))
        scenes.append(EvalScene(i, episode_seed, peg))
    return scenes

