"""One grasp experience (:class:`Transition`) and the digest of a pair of heightmaps
(:func:`maps_digest`), which a checkpoint records to check that a host re-renders a replayed
scene bit for bit. :mod:`vgs.grasping.replay` stores transitions and re-exports both names."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from vgs.errors import ConfigError


@dataclass(frozen=True)
class Transition:
    """One grasp experience (s, a, r, s', done).

    Attributes:
        color: RGB heightmap of s, uint8 (H, W, 3).
        depth: Height map of s [m], float32 (H, W).
        action: Executed action (rotation index, row, col).
        reward: Reward R(s, a) = r_G + r_AM.
        next_color: RGB heightmap of s', or ``None`` when no next state is stored.
        next_depth: Height map of s' [m], or ``None``.
        done: True if s is terminal for bootstrapping: the TD target is then y = r.
        scene: Seed of the scene the maps of s were rendered from, or ``None``; a
            scene-keyed :class:`ReplayBuffer` stores this instead of the maps.
    """

    color: np.ndarray
    depth: np.ndarray
    action: tuple[int, int, int]
    reward: float
    next_color: np.ndarray | None = None
    next_depth: np.ndarray | None = None
    done: bool = True
    scene: int | None = None

    def __post_init__(self) -> None:
        if self.color.dtype != np.uint8 or self.color.ndim != 3 or self.color.shape[2] != 3:
            raise ConfigError("transition.color", "must be uint8 (H, W, 3)")
        if self.depth.shape != self.color.shape[:2]:
            raise ConfigError("transition.depth", "must be (H, W) like the colour map")
        if (self.next_color is None) != (self.next_depth is None):
            raise ConfigError("transition.next_color", "give both next maps or neither")
        if self.next_color is not None and (
            self.next_color.shape != self.color.shape or self.next_depth.shape != self.depth.shape
        ):
            raise ConfigError("transition.next_color", "next maps must match the current ones")
        if len(self.action) != 3:
            raise ConfigError("transition.action", "must be (rotation, row, col)")
        k, row, col = (int(a) for a in self.action)
        h, w = self.depth.shape
        if k < 0 or not (0 <= row < h and 0 <= col < w):
            raise ConfigError("transition.action", f"{self.action} outside the {h} x {w} map")
        if not np.isfinite(self.reward):
            raise ConfigError("transition.reward", f"must be finite, got {self.reward!r}")

    @property
    def has_next(self) -> bool:
        """True if a next state is stored."""
        return self.next_color is not None


def maps_digest(color: np.ndarray, depth: np.ndarray) -> str:
    """SHA-256 of a pair of heightmaps (shapes, dtypes and bytes)."""
    h = hashlib.sha256()
    for a in (color, depth):
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()
