"""The pieces of the DQN that hold no network (paper eq. 4-11): the Huber TD loss on the executed
pixel, the epsilon schedule, the opposite rotation of a two-finger grasp and the Delta Q
convergence monitor. :class:`vgs.grasping.agent.GraspAgent` uses them; :mod:`vgs.grasping.agent`
re-exports the names."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor

from vgs.config import AgentConfig
from vgs.errors import ConfigError

HUBER_BETA = 1.0


def opposite_rotation(k: int, num_rotations: int) -> int | None:
    """(k + R/2) mod R for even R (the same two-finger grasp turned by 180 degrees), else None."""
    if num_rotations % 2 or num_rotations < 2:
        return None
    return (k + num_rotations // 2) % num_rotations


def td_loss(q: Tensor, rotations: Sequence[int], row: int, col: int, target: float) -> Tensor:
    """Huber loss at one pixel of the given rotations, summed.

    L = sum_{r in rotations} huber(q[r, row, col] - target), huber(x) = 0.5 x^2 for |x| < 1 and
    |x| - 0.5 otherwise (smooth L1, beta = 1). All other entries of q get zero gradient.

    Args:
        q: Q maps (n, H, W).
        rotations: Indices into the first axis of q.
        row: Pixel row.
        col: Pixel column.
        target: TD target y.
    """
    values = q[list(rotations), row, col]
    y = torch.full_like(values, float(target))
    return F.smooth_l1_loss(values, y, reduction="sum", beta=HUBER_BETA)


def epsilon_schedule(episode: int, total_episodes: int, cfg: AgentConfig) -> float:
    """Exploration rate of an episode (module docstring).

    Raises:
        ConfigError: On a negative episode or total_episodes < 1.
    """
    if episode < 0:
        raise ConfigError("agent.episode", f"must be >= 0, got {episode}")
    if total_episodes < 1:
        raise ConfigError("train.episodes", f"must be >= 1, got {total_episodes}")
    if episode < cfg.random_episodes:
        return 1.0
    span = max(1, total_episodes - cfg.random_episodes - 1)
    frac = min(1.0, (episode - cfg.random_episodes) / span)
    return cfg.epsilon_start + (cfg.epsilon_end - cfg.epsilon_start) * frac


class DeltaQMonitor:
    """Convergence rule of the paper: Delta Q stays below a threshold over a window.

    Converged once the last ``window`` recorded values are all < ``threshold``.

    Args:
        threshold: ``agent.delta_q_threshold``.
        window: ``agent.delta_q_window`` (number of values).

    Raises:
        ConfigError: On a threshold <= 0 or a window < 1.
    """

    def __init__(self, threshold: float, window: int) -> None:
        if not (math.isfinite(threshold) and threshold > 0):
            raise ConfigError("agent.delta_q_threshold", f"must be > 0, got {threshold!r}")
        if window < 1:
            raise ConfigError("agent.delta_q_window", f"must be >= 1, got {window}")
        self.threshold = float(threshold)
        self.window = int(window)
        self._values: deque[float] = deque(maxlen=self.window)

    @classmethod
    def from_config(cls, cfg: AgentConfig) -> DeltaQMonitor:
        """Monitor with ``cfg.delta_q_threshold`` and ``cfg.delta_q_window``."""
        return cls(cfg.delta_q_threshold, cfg.delta_q_window)

    def update(self, delta_q: float) -> bool:
        """Record one Delta Q; returns :attr:`converged`."""
        if not math.isfinite(delta_q) or delta_q < 0:
            raise ConfigError("agent.delta_q", f"must be a finite value >= 0, got {delta_q!r}")
        self._values.append(float(delta_q))
        return self.converged

    @property
    def converged(self) -> bool:
        """True when the window is full and every value in it is below the threshold."""
        return len(self._values) == self.window and max(self._values) < self.threshold

    @property
    def mean(self) -> float:
        """Mean Delta Q over the current window (NaN when empty)."""
        return float(np.mean(self._values)) if self._values else math.nan

    @property
    def max(self) -> float:
        """Largest Delta Q in the current window (NaN when empty): the convergence rule's."""
        return float(max(self._values)) if self._values else math.nan

    def state_dict(self) -> dict[str, Any]:
        """Picklable state."""
        return {"threshold": self.threshold, "window": self.window, "values": list(self._values)}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict`."""
        self.threshold = float(state["threshold"])
        self.window = int(state["window"])
        # (the checkpoint's strict JSON holds a NaN as null)
        self._values = deque((math.nan if v is None else float(v) for v in state["values"]),
                             maxlen=self.window)
