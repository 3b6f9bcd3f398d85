"""A flat grasp action with the exact mask of the peg's pixels, for sb3-contrib's MaskablePPO.

MaskablePPO masks a ``MultiDiscrete`` action dimension by dimension (rows and columns on their
own, :meth:`GraspAssembleEnv.action_masks`), which admits the peg's bounding box.
:class:`FlatGraspAction` numbers the (map k, row i, column j) triples of
``MultiDiscrete([n, H, W])`` as one ``Discrete(n H W)`` action

    a = (k H + i) W + j,    k = a // (H W),  i = (a // W) mod H,  j = a mod W,

so ``action_masks()`` can give the peg's pixels exactly: the pixel mask, flattened row by row,
once per map.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from vgs.errors import ConfigError


class FlatGraspAction(gym.ActionWrapper):
    """``Discrete(n H W)`` over a ``vgs/GraspAssemble-v0`` environment (module docstring).

    Args:
        env: The environment (made by ``gymnasium.make`` or a :class:`GraspAssembleEnv`).

    Raises:
        ConfigError: ``env`` if its action space is not ``MultiDiscrete([n, H, W])``.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        space = env.action_space
        if not (isinstance(space, spaces.MultiDiscrete) and space.shape == (3,)):
            raise ConfigError("env", f"expected the MultiDiscrete([n, H, W]) action of "
                                     f"vgs/GraspAssemble-v0, got {space}")
        self.shape: tuple[int, int, int] = tuple(int(v) for v in space.nvec)  # type: ignore
        self.action_space = spaces.Discrete(int(np.prod(self.shape)))

    def action(self, action: Any) -> np.ndarray:
        """The flat action ``a`` as ``(k, i, j)``, int64 (3,).

        Raises:
            ConfigError: ``action`` if it is not one integer in ``[0, n H W)``.
        """
        value = np.asarray(action)
        if value.size != 1 or value.dtype == np.bool_ or not np.issubdtype(value.dtype,
                                                                           np.integer):
            raise ConfigError("action", f"must be one integer, got {action!r:.60}")
        flat = int(value.reshape(()))
        if not 0 <= flat < self.action_space.n:
            raise ConfigError("action", f"{flat} is outside {self.action_space}")
        return np.array(np.unravel_index(flat, self.shape), dtype=np.int64)

    def flat(self, k: int, row: int, col: int) -> int:
        """The flat action of map ``k``, pixel ``(row, col)`` (the inverse of :meth:`action`)."""
        return int(np.ravel_multi_index((k, row, col), self.shape))

    def action_masks(self) -> np.ndarray:
        """The exact mask, bool (n H W,): the peg's pixels (``info["action_mask"]``) per map.

        Raises:
            gymnasium.error.ResetNeeded: Before the first ``reset``.
        """
        mask = self.env.get_wrapper_attr("pixel_mask")()
        return np.tile(mask.ravel(), self.shape[0])
