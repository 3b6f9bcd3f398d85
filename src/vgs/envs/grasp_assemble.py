"""``vgs/GraspAssemble-v0``: one grasp followed by its assembly per episode.

Observation: ``{"color": uint8 (H, W, 3), "depth": float32 (H, W) heights [m]}``, the camera's
heightmaps. Action: ``(rotation k, row i, col j)`` as the grasp network outputs it; pixel
(i, j) is the grasp point and theta_k = 2 pi k / R the closing direction. Reward: paper eq. 5,
``r_G`` for a successful grasp plus, in ``vgs`` mode, ``r_AM`` when the assembly succeeded in
less than ``threshold_s``. Every step terminates the episode; ``info["record"]`` is the episode
record
(``EpisodeRecord.to_row()``, with None for undefined fields).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from vgs.assembly.episode import EpisodeRunner, GraspCommand
from vgs.config import ExperimentConfig, profile
from vgs.errors import ConfigError
from vgs.grasping.rewards import MODES, grasp_reward
from vgs.sim.camera import Heightmap

DEFAULT_THRESHOLD_S = 60.0  # assembly-time threshold when neither argument nor config gives one
MAX_HEIGHT = 0.5  # upper bound of the depth observation [m]


class GraspAssembleEnv(gym.Env):
    """Grasp-and-assemble environment.

    Args:
        cfg: Experiment configuration (default: the ``smoke`` profile).
        mode: ``vgs`` (grasp and assembly reward) or ``baseline`` (grasp reward only).
        threshold_s: Assembly-time threshold [s]; default ``cfg.reward.threshold_s`` or
            :data:`DEFAULT_THRESHOLD_S`.
    """

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(self, cfg: ExperimentConfig | None = None, mode: str = "vgs",
                 threshold_s: float | None = None) -> None:
        if mode not in MODES:
            raise ConfigError("mode", f"must be one of {MODES}, got {mode!r}")
        self.cfg = cfg or profile("smoke")
        self.mode = mode
        threshold = threshold_s if threshold_s is not None else self.cfg.reward.threshold_s
        self.threshold_s = DEFAULT_THRESHOLD_S if threshold is None else float(threshold)
        if not self.threshold_s > 0:
            raise ConfigError("reward.threshold_s", "must be > 0")
        size = self.cfg.cell.camera.size
        rotations = self.cfg.network.num_rotations
        self.observation_space = spaces.Dict({
            "color": spaces.Box(0, 255, (size, size, 3), np.uint8),
            "depth": spaces.Box(0.0, MAX_HEIGHT, (size, size), np.float32),
        })
        self.action_space = spaces.MultiDiscrete([rotations, size, size])
        self.runner = EpisodeRunner(self.cfg)
        self._seed = 0
        self._hm: Heightmap | None = None

    def _obs(self, hm: Heightmap) -> dict[str, np.ndarray]:
        return {"color": hm.color.copy(),
                "depth": np.clip(hm.depth, 0.0, MAX_HEIGHT).astype(np.float32)}

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[dict[str, np.ndarray], dict]:
        super().reset(seed=seed)
        self._seed = int(self.np_random.integers(0, 2**31 - 1))
        self._hm = self.runner.observe(self._seed)
        return self._obs(self._hm), {"episode_seed": self._seed}

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict]:
        if self._hm is None:
            raise RuntimeError("call reset() before step()")
        k, row, col = (int(a) for a in np.asarray(action).reshape(3))
        rotations = self.cfg.network.num_rotations
        angle = 2 * np.pi * k / rotations
        hm = self._hm
        x, y = hm.pixel_to_world(row, col)
        command = GraspCommand(float(x), float(y), float(angle - np.pi / 2))
        record, _, _ = self.runner.run(self._seed, lambda _hm: command)
        time_ok = record.assembly_time if record.success else None
        r_g, r_am = grasp_reward(record.grasp_success, time_ok, self.threshold_s, self.mode,
                                 self.cfg.reward)
        # Undefined fields (NaN, e.g. no grasp offset without a grasp) are given as None.
        row = {k: (None if isinstance(v, float) and np.isnan(v) else v)
               for k, v in record.to_row().items()}
        return self._obs(hm), float(r_g + r_am), True, False, {"record": row}
