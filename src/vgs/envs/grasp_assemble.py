"""``vgs/GraspAssemble-v0``: one grasp followed by its assembly per episode.

Made with ``gymnasium.make("vgs/GraspAssemble-v0", cfg="quick", mode="vgs",
condition="nominal", overrides={"cell.peg.mass": 0.6})`` after ``import vgs``.

Observation (``Dict``), the overhead camera's heightmaps as images (H = W =
``cell.camera.size``, 224 by default; rows along +y, columns along +x):

* ``color``: uint8 (H, W, 3), RGB;
* ``depth``: uint8 (H, W, 1), the height above the table in units of :data:`DEPTH_UNIT`
  (0.5 mm; 0-127.5 mm, the lying peg is 30 mm high). The full-precision heightmap is
  ``env.unwrapped.heightmap``.

Action (``MultiDiscrete([n, H, W])``): ``(map k, row i, col j)`` as the grasp network outputs
it; pixel (i, j) is the grasp point. With ``network.action = "position"`` (the paper's, the
default) n = 1, k = 0 and the jaws close across the peg's axis as perceived in the same
heightmap; with ``"rotation"`` n = R = ``network.num_rotations`` and theta_k = 2 pi k / R is the
closing direction. ``info["action_mask"]`` (bool (H, W)) marks the pixels on the peg, where the
agent of the paper grasps; an action elsewhere grasps at the table and fails. The mask is the
same for every map; :meth:`GraspAssembleEnv.action_masks` gives sb3-contrib's MaskablePPO its
per-dimension form, :class:`vgs.envs.masking.FlatGraspAction` a flat action masked exactly.

Grasp-only episodes (``assemble=False``) end after the grasp (``failure_reason``
``no_assembly``): the reward is r_G alone, whatever the mode. With the assembly (the default)
an episode runs the same code as ``vgs evaluate``'s (unchanged).

Reward: paper eq. 5 with training's code (:func:`vgs.grasping.rewards.episode_reward`):
``r_G`` for a successful grasp plus, in ``vgs`` mode, ``r_AM`` when the assembly succeeded
faster than the threshold. The threshold follows training's rule
(:func:`vgs.grasping.rewards.next_threshold`): ``reward.threshold_s`` when given, else the
running ``reward.threshold_percentile`` of the successful assembly times of this env's first
``agent.random_episodes`` episodes, frozen after them (``env.unwrapped.threshold_s``; no r_AM
before a first time is known). A seeded ``reset(seed=...)`` starts the run over (episode count
and times cleared), so a seeded env reproduces its episodes and rewards.

Conditions (paper 4.2, as ``vgs evaluate`` draws them): ``nominal``; ``mass``, the peg's mass
times 1 +- ``eval.mass_range``; ``length``, its length times 1 +- ``eval.length_range`` with
the mass following; one uniform draw per episode.

Every step ends the episode (``terminated=True``); ``info["record"]`` is the episode record
(``EpisodeRecord.to_row()``: the column names and units of :mod:`vgs.columns`, ``None`` for
undefined values). Rendering (:meth:`GraspAssembleEnv.render`, from the ``perspective``
camera, only when called; EGL where no display is set, :func:`vgs.render.headless_default`):
``render_mode="rgb_array"`` draws the cell's current state (after ``reset``: the peg on the
table; after ``step``: the end of the assembly); ``"rgb_array_list"`` gives after ``step`` the
frames of the whole grasp and assembly, drawn from the states the episode recorded (one per
control tick, ``Trace.qpos``; never drawn inside the physics loop), one every
``render_speed / metadata["render_fps"]`` simulated seconds, time and phase written on each;
after ``reset`` the one frame of the peg on the table. The list stays until the next ``reset``
or ``step``: with Gymnasium's ``RecordVideo`` call ``env.render()`` after the step to record it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from vgs.assembly.episode import EpisodeRunner
from vgs.config import CONDITIONS, ExperimentConfig, PegConfig, condition_peg, override, profile
from vgs.errors import ConfigError
from vgs.grasping.actions import closing_angle, peg_mask
from vgs.grasping.rewards import MODES, episode_reward, next_threshold
from vgs.rollout.policies import pixel_command
from vgs.sim.camera import Heightmap
from vgs.validate import check_config

DEPTH_UNIT = 0.0005  # metres per unit of the uint8 depth observation
RENDER_MODES = ("rgb_array", "rgb_array_list")
VIDEO_FPS = 15  # frames per second of an rgb_array_list episode (metadata["render_fps"])


def make_config(cfg: ExperimentConfig | str | None,
                overrides: Mapping[str, Any] | None = None) -> ExperimentConfig:
    """The configuration of a profile name (or a configuration) with dotted-path overrides.

    Args:
        cfg: A profile name (``smoke``, ``quick``, ``medium``, ``paper``), a configuration,
            or ``None`` for ``paper``.
        overrides: ``{"cell.peg.mass": 0.6, ...}``, applied in order.

    Raises:
        ConfigError: On an unknown profile, field or an invalid value.
    """
    if cfg is None or isinstance(cfg, str):
        cfg = profile(cfg or "paper")
    elif not isinstance(cfg, ExperimentConfig):
        raise ConfigError("cfg", f"expected a profile name or an ExperimentConfig, got "
                                 f"{type(cfg).__name__}")
    if overrides is not None and not isinstance(overrides, Mapping):
        raise ConfigError("overrides", f"expected a mapping of dotted paths to values, e.g. "
                                       f"{{'cell.peg.mass': 0.6}}, got {type(overrides).__name__}")
    for path, value in (overrides or {}).items():
        if not isinstance(path, str):
            raise ConfigError("overrides", f"a key must be a dotted path, got {path!r:.40}")
        try:
            cfg = override(cfg, path, value)
        except (TypeError, ValueError, OverflowError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(path, f"invalid value ({type(exc).__name__}: {exc})") from None
    # the command line's checks: types, seeds, bounds
    return check_config(cfg)


def depth_image(depth: np.ndarray) -> np.ndarray:
    """Heights [m] (H, W) -> the uint8 (H, W, 1) depth observation in :data:`DEPTH_UNIT`."""
    units = np.rint(np.clip(depth, 0.0, 255 * DEPTH_UNIT) / DEPTH_UNIT)
    return units.astype(np.uint8)[..., None]


class GraspAssembleEnv(gym.Env[dict[str, np.ndarray], np.ndarray]):
    """Grasp-and-assemble environment (module docstring).

    Args:
        cfg: Profile name or configuration (default: the ``paper`` profile).
        mode: ``vgs`` (grasp and assembly reward) or ``baseline`` (grasp reward only).
        condition: ``nominal``, ``mass`` or ``length``.
        overrides: Configuration overrides by dotted path, e.g. ``{"cell.peg.mass": 0.6}``.
        threshold_s: Fixed assembly-time threshold [s] (sets ``reward.threshold_s``);
            default: the configured one, else derived as in training.
        render_mode: ``None``, ``"rgb_array"`` or ``"rgb_array_list"``.
        render_width: Width of rendered frames [px].
        render_height: Height of rendered frames [px].
        render_speed: Simulated seconds per second of video (``rgb_array_list``).
        assemble: ``False`` ends each episode after the grasp (grasp-only episodes, module
            docstring).

    Raises:
        ConfigError: On a bad mode, condition, render mode or configuration.
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": VIDEO_FPS}

    def __init__(self, cfg: ExperimentConfig | str | None = None, mode: str = "vgs",
                 condition: str = "nominal", overrides: Mapping[str, Any] | None = None,
                 threshold_s: float | None = None, render_mode: str | None = None,
                 render_width: int = 480, render_height: int = 360,
                 render_speed: float = 4.0, assemble: bool = True) -> None:
        if mode not in MODES:
            raise ConfigError("mode", f"must be one of {MODES}, got {mode!r}")
        if condition not in CONDITIONS:
            raise ConfigError("condition", f"must be one of {CONDITIONS}, got {condition!r}")
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ConfigError("render_mode", f"must be None or one of {RENDER_MODES}, got "
                                             f"{render_mode!r}")
        cfg = make_config(cfg, overrides)
        if threshold_s is not None:
            cfg = override(cfg, "reward.threshold_s", float(threshold_s))
        self.cfg = cfg
        self.mode = mode
        self.condition = condition
        self.render_mode = render_mode
        self.render_size = (int(render_width), int(render_height))
        if not isinstance(assemble, (bool, np.bool_)):
            raise ConfigError("assemble", f"must be True or False, got {assemble!r}")
        self.assemble = bool(assemble)
        if not (math.isfinite(render_speed) and render_speed > 0):
            raise ConfigError("render_speed", f"must be > 0, got {render_speed!r}")
        self.render_speed = float(render_speed)
        self._trace: Any = None  # the last step's states (rgb_array_list)
        self._frames: list[np.ndarray] | None = None
        size = cfg.cell.camera.size
        self.observation_space = spaces.Dict({
            "color": spaces.Box(0, 255, (size, size, 3), np.uint8),
            "depth": spaces.Box(0, 255, (size, size, 1), np.uint8),
        })
        self.action_space = spaces.MultiDiscrete([cfg.network.q_maps, size, size])
        self.runner = EpisodeRunner(cfg)
        self.threshold_s: float | None = cfg.reward.threshold_s
        self.episodes = 0
        self._times: list[float] = []
        self._seed = 0
        self._peg: PegConfig = cfg.cell.peg
        self.heightmap: Heightmap | None = None
        self._done = False  # whether the episode of the last reset has ended
        self._renderer: Any = None
        self._renderer_key: tuple[float, float] | None = None

    def _obs(self, hm: Heightmap) -> dict[str, np.ndarray]:
        return {"color": hm.color.copy(), "depth": depth_image(hm.depth)}

    def _info(self, hm: Heightmap) -> dict[str, Any]:
        return {"episode_seed": self._seed, "action_mask": peg_mask(hm.depth),
                "peg_mass_kg": self._peg.mass, "peg_length_mm": self._peg.length * 1000.0}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Place a new peg (and hole); a ``seed`` also starts the run over (module docstring)."""
        super().reset(seed=seed)
        if seed is not None:
            self.episodes = 0
            self._times = []
            self.threshold_s = self.cfg.reward.threshold_s
        self._seed = int(self.np_random.integers(0, 2**31 - 1))
        self._peg = condition_peg(self.cfg.cell.peg, self.cfg.eval, self.condition,
                                  float(self.np_random.uniform(-1.0, 1.0)))
        self.heightmap = self.runner.observe(self._seed, self._peg)
        self._trace, self._frames = None, None
        self._done = False
        return self._obs(self.heightmap), self._info(self.heightmap)

    def pixel_mask(self) -> np.ndarray:
        """The pixels on the peg in the current heightmap: ``info["action_mask"]``, bool (H, W).

        Raises:
            gymnasium.error.ResetNeeded: Before the first ``reset``.
        """
        if self.heightmap is None:
            raise gym.error.ResetNeeded("call reset() before action_masks()")
        return peg_mask(self.heightmap.depth)

    def action_masks(self) -> np.ndarray:
        """sb3-contrib's ``MaskablePPO`` mask of the ``MultiDiscrete([n, H, W])`` action, bool
        (n + H + W,): every map, then the rows and the columns that hold a peg pixel.

        MaskablePPO masks each dimension on its own, so this admits the peg's bounding box, a
        superset of the peg's pixels (mostly table for a diagonal peg);
        :class:`vgs.envs.masking.FlatGraspAction` gives the exact mask of a flat action.
        """
        mask = self.pixel_mask()
        maps = np.ones(int(self.action_space.nvec[0]), dtype=bool)
        return np.concatenate([maps, mask.any(axis=1), mask.any(axis=0)])

    def _check_action(self, action: Any) -> tuple[int, int, int]:
        """``(rotation, row, col)`` of an action: three integers (a NumPy integer array or a
        sequence of ints; no bools, no fractions) inside the action space.

        Raises:
            ConfigError: ``action``, saying what is wrong.
        """
        if isinstance(action, (list, tuple)) and any(
                isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer))
                for a in action):
            raise ConfigError("action", f"must hold integers, got {action!r}")
        try:
            values = np.asarray(action)
        except (TypeError, ValueError) as exc:
            raise ConfigError("action", f"is not an array of three integers ({exc})") from None
        if values.shape != (3,):
            raise ConfigError("action", f"must have shape (3,) (rotation, row, col), got shape "
                                        f"{values.shape}")
        if values.dtype == np.bool_ or not np.issubdtype(values.dtype, np.integer):
            raise ConfigError("action", f"must hold integers, got {values.dtype} "
                                        f"{values.tolist()!r}")
        k, row, col = (int(a) for a in values)
        if not self.action_space.contains(np.array([k, row, col], dtype=np.int64)):
            raise ConfigError("action", f"{(k, row, col)} is outside {self.action_space}")
        return k, row, col

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool,
                                         dict[str, Any]]:
        """Grasp at the action's pixel and rotation, assemble, end the episode."""
        hm = self.heightmap
        if hm is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        if self._done:
            raise gym.error.ResetNeeded("the episode has ended (every step ends one); call "
                                        "reset() before step()")
        k, row, col = self._check_action(action)
        network = self.cfg.network
        command = pixel_command(hm, row, col, closing_angle(network.action, k,
                                                            network.num_rotations, hm.depth))
        listing = self.render_mode == "rgb_array_list"  # record the states to draw them after
        record, robot, _ = self.runner.run(self._seed, lambda _hm: command, peg=self._peg,
                                           trace=listing, assemble=self.assemble)
        self._trace, self._frames = (robot.trace if listing else None), None
        time_ok = record.assembly_time if record.success else None
        exploring = self.episodes < self.cfg.agent.random_episodes
        self.threshold_s = next_threshold(self._times, self.threshold_s, time_ok, exploring,
                                          self.cfg.reward)
        r_g, r_am = episode_reward(record.grasp_success, time_ok, self.threshold_s, self.mode,
                                   self.cfg.reward)
        self.episodes += 1
        self._done = True
        # Undefined fields (NaN, e.g. no grasp offset without a grasp) are given as None.
        row_values = {key: (None if isinstance(v, float) and math.isnan(v) else v)
                      for key, v in record.to_row().items()}
        info = {**self._info(hm), "record": row_values, "r_grasp": r_g, "r_assembly": r_am}
        return self._obs(hm), float(r_g + r_am), True, False, info

    def render(self) -> np.ndarray | list[np.ndarray] | None:  # type: ignore[override]
        """The cell from the ``perspective`` camera: its current state (``rgb_array``), or the
        frames of the last episode (``rgb_array_list``, module docstring).

        Raises:
            GLUnavailableError: If no OpenGL context can be made.
        """
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; make the env with "
                            "render_mode='rgb_array' or 'rgb_array_list'")
            return None
        cell, _ = self.runner.cell(self._peg)
        renderer = self._scene_renderer()
        if self.render_mode == "rgb_array":
            return renderer.frame(cell.data.qpos, cell.data.mocap_pos)
        if self._frames is None:
            self._frames = self._episode_frames(renderer, cell.data.qpos, cell.data.mocap_pos)
        return list(self._frames)

    def _scene_renderer(self) -> Any:
        from vgs.render import SceneRenderer

        key = (self._peg.mass, self._peg.length)
        if self._renderer is None or self._renderer_key != key:
            self.close()
            self._renderer = SceneRenderer(replace(self.cfg.cell, peg=self._peg),
                                           *self.render_size)
            self._renderer_key = key
        return self._renderer

    def _episode_frames(self, renderer: Any, qpos: np.ndarray, mocap: np.ndarray
                        ) -> list[np.ndarray]:
        """The last step's recorded states drawn, or the current state after a reset."""
        from vgs.render import annotate, frame_indices

        trace = self._trace
        if trace is None or not trace.qpos:
            return [renderer.frame(qpos, mocap)]
        mocap = np.array(mocap, copy=True)
        indices = frame_indices(np.asarray(trace.time), VIDEO_FPS, self.render_speed)
        return [annotate(renderer.frame(trace.qpos[i], mocap),
                         [f"t = {trace.time[i]:5.1f} s (x{self.render_speed:g})",
                          f"phase: {trace.phase[i]}"]) for i in indices]

    def close(self) -> None:
        """Free the renderer's OpenGL context, if one was made."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
            self._renderer_key = None
