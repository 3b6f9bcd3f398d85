"""Grasp and assembly rewards (paper eq. 5) and the assembly-time threshold.

The reward of a grasp is R(s_t, a_t) = r^G_{t+1} + r^AM_{t+1} with

    r^G  = cfg.grasp     (0.3)  if the grasp succeeded, else 0,
    r^AM = cfg.assembly  (0.7)  if mode == "vgs", the grasp and the assembly succeeded and the
                                assembly time t satisfies t < threshold, else 0.

The baseline (paper 3.2) is trained with the same grasp reward but never receives r^AM.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from vgs.config import RewardConfig
from vgs.errors import ConfigError

MODES = ("vgs", "baseline")


def grasp_reward(
    success: bool,
    assembly_time_s: float | None,
    threshold_s: float | None,
    mode: str,
    cfg: RewardConfig,
) -> tuple[float, float]:
    """The two reward terms of one episode.

    Args:
        success: The grasp held the peg.
        assembly_time_s: Duration of a successful assembly [s]; ``None`` if the assembly was
            not attempted or failed.
        threshold_s: Assembly-time threshold [s]; ``None`` falls back to ``cfg.threshold_s``.
        mode: ``"vgs"`` (grasp and assembly rewards) or ``"baseline"`` (grasp reward only).
        cfg: Reward magnitudes.

    Returns:
        ``(r_grasp, r_assembly)``; the total reward is their sum.

    Raises:
        ConfigError: ``reward.mode`` on an unknown mode; ``reward.assembly_time_s`` on a
            negative or non-finite time; ``reward.threshold_s`` if the VGS mode needs a
            threshold and none is given or it is not positive.
    """
    if mode not in MODES:
        raise ConfigError("reward.mode", f"must be one of {MODES}, got {mode!r}")
    if assembly_time_s is not None and not (
        np.isfinite(assembly_time_s) and assembly_time_s >= 0
    ):
        raise ConfigError("reward.assembly_time_s", f"must be >= 0, got {assembly_time_s!r}")
    r_grasp = cfg.grasp if success else 0.0
    if mode == "baseline" or not success or assembly_time_s is None:
        return r_grasp, 0.0
    threshold = cfg.threshold_s if threshold_s is None else threshold_s
    if threshold is None:
        raise ConfigError("reward.threshold_s", "the vgs mode needs an assembly-time threshold")
    if not (np.isfinite(threshold) and threshold > 0):
        raise ConfigError("reward.threshold_s", f"must be > 0, got {threshold!r}")
    r_assembly = cfg.assembly if assembly_time_s < threshold else 0.0
    return r_grasp, r_assembly


def derive_threshold(times: Iterable[float], percentile: float) -> float:
    """Assembly-time threshold from the exploration phase: a percentile of the times.

    Uses numpy's default (linear) percentile interpolation over the finite times: for sorted
    times t_0 <= ... <= t_{n-1} and q = percentile / 100, the threshold is
    t_j + (q (n - 1) - j) (t_{j+1} - t_j) with j = floor(q (n - 1)).

    Args:
        times: Durations of successful assemblies [s]; non-finite entries (failures recorded
            as NaN or inf) are ignored.
        percentile: In (0, 100) (``reward.threshold_percentile``).

    Returns:
        The threshold [s].

    Raises:
        ConfigError: ``reward.threshold_percentile`` outside (0, 100);
            ``reward.threshold_s`` if no finite time is given or a time is negative.
    """
    if not 0.0 < percentile < 100.0:
        raise ConfigError("reward.threshold_percentile", f"must lie in (0, 100), got {percentile}")
    values = np.asarray(list(times), dtype=np.float64)
    values = values[np.isfinite(values)]
    if values.size == 0:
        raise ConfigError("reward.threshold_s", "no finite assembly time to derive it from")
    if np.any(values < 0):
        raise ConfigError("reward.threshold_s", "assembly times must be >= 0")
    return float(np.percentile(values, percentile))


def next_threshold(times: list[float], threshold: float | None, time_ok: float | None,
                   exploring: bool, cfg: RewardConfig) -> float | None:
    """Training's assembly-time threshold after one more episode.

    The rule: ``cfg.threshold_s`` when it is given; otherwise, while the agent explores at
    random (the first ``agent.random_episodes`` episodes), the running ``threshold_percentile``
    of the successful assembly times seen so far (:func:`derive_threshold`), frozen when that
    phase ends. Used by training (:mod:`vgs.experiments.train`) and the Gymnasium env
    (:mod:`vgs.envs.grasp_assemble`).

    Args:
        times: Successful exploration-phase assembly times so far [s]; ``time_ok`` is appended
            to it while exploring.
        threshold: The threshold before this episode (``None``: none known yet).
        time_ok: This episode's assembly time if the assembly succeeded, else ``None``.
        exploring: Whether this episode belongs to the random-exploration phase.
        cfg: Reward configuration.

    Returns:
        The threshold after this episode; ``None`` while no successful time is known.
    """
    if cfg.threshold_s is not None:
        return cfg.threshold_s
    if exploring and time_ok is not None:
        times.append(time_ok)
    if exploring or threshold is None:
        return derive_threshold(times, cfg.threshold_percentile) if times else None
    return threshold


def episode_reward(success: bool, time_ok: float | None, threshold: float | None, mode: str,
                   cfg: RewardConfig) -> tuple[float, float]:
    """The two reward terms of one episode as training gives them.

    As :func:`grasp_reward`, except that before any threshold is known (``threshold`` is
    ``None``) no r_AM can be earned, in either mode.
    """
    return grasp_reward(success, time_ok, threshold,
                        mode if threshold is not None else "baseline", cfg)


__all__ = ["MODES", "derive_threshold", "episode_reward", "grasp_reward", "next_threshold"]
