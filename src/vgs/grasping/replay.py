"""Prioritised experience replay ranked by surprise, as in visual-pushing-grasping (VPG).

Every stored transition carries its surprise, the absolute TD error Delta Q = |y - Q_eva(s, a)|
of its last update (paper eq. 10). To replay, the n candidate transitions are sorted by
surprise in ascending order (ties: older first) and the rank position

    i = round(u * (n - 1)),   u ~ Power(a)  (density a * u^(a - 1) on [0, 1]),

is drawn, with a = 2 by default (VPG's ``pow_law_exp``). Since P(u <= x) = x^a, the transition
at rank i (0 = least surprising) is drawn with probability

    P(i) = F((i + 1/2) / (n - 1)) - F((i - 1/2) / (n - 1)),   F(x) = clip(x, 0, 1)^a,

which for a = 2 grows linearly with the rank, P(i) ~ 2 i / (n - 1)^2: the most surprising
transitions are replayed most often, none is starved, and the ranking (unlike the raw errors)
is insensitive to the scale of the rewards. After a replay, the caller writes the new Delta Q
back with :meth:`ReplayBuffer.update_surprise`.

The buffer has a fixed capacity; when it is full a new transition overwrites the oldest one
(ring buffer). It keeps transitions in one of two ways:

* **maps** (default): the heightmaps themselves. Arrays are allocated on the first insertion;
  the next-state arrays only when a first transition with a next state arrives. A 224 x 224
  transition takes 150,528 B colour + 200,704 B depth = 351 kB, twice that with a next state.
* **scenes** (``render`` given): only what re-creates the heightmaps, the scene seed of each
  transition (:attr:`Transition.scene`), with its action, reward, done flag, surprise and
  insertion serial: 58 B a transition. :meth:`ReplayBuffer.get` re-renders the maps with
  ``render(scene)``, which must give bit-identical maps for a seed (the training loop passes
  the observation path that produced them, :meth:`vgs.assembly.episode.EpisodeRunner.observe`).
  The last ``cache_size`` maps used (added or re-rendered) stay in memory (least recently used
  out first), so a transition replayed again soon is not rendered twice. Terminal transitions
  only: a next state would need its own scene.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from vgs.errors import ConfigError
from vgs.grasping.transition import Transition, maps_digest

_COMMON = ("has_next", "action", "reward", "done", "surprise", "serial")
_MAP_ARRAYS = ("color", "depth", "next_color", "next_depth", *_COMMON)
_SCENE_ARRAYS = ("scene", *_COMMON)

Renderer = Callable[[int], tuple[np.ndarray, np.ndarray]]
"""``render(scene) -> (color, depth)``: the heightmaps of a scene seed, bit-identical each time."""

DEFAULT_CACHE = 32  # re-rendered maps kept by a scene-keyed buffer (11 MB at 224 x 224)
CACHE_BYTES = 2 * 1024**3  # memory a training run may spend on cached maps (cache_size_for)


def cache_size_for(capacity: int, pixels: int, budget: int = CACHE_BYTES) -> int:
    """Maps a scene-keyed buffer of ``capacity`` transitions keeps in memory: all of them when
    they fit in ``budget`` bytes, else as many as fit (at least :data:`DEFAULT_CACHE`).

    A ``pixels`` x ``pixels`` map takes ``7 pixels^2`` bytes (uint8 colour, float32 depth):
    351 kB at 224, so a 5000-transition buffer fits in 1.76 GB. Transitions enter the cache when
    they are added, so a cache that holds the whole buffer never renders in one process (a
    resumed one renders each map once, on its first replay); replays return the same maps
    either way, so the size changes time and memory, never a result.
    """
    per_map = 7 * pixels * pixels
    return max(DEFAULT_CACHE, min(int(capacity), int(budget) // per_map))


class ReplayBuffer:
    """Fixed-capacity ring buffer of transitions with rank-based prioritised sampling.

    Args:
        capacity: Largest number of stored transitions (``agent.replay_capacity``).
        power: Exponent a of the power law over surprise ranks (VPG: 2); a = 1 is uniform.
        render: Keep scene seeds instead of heightmaps and re-render the maps of a scene with
            this function when a transition is read (module docstring); ``None`` keeps maps.
        cache_size: Re-rendered maps kept in memory by a scene-keyed buffer (0: none).

    Raises:
        ConfigError: On a capacity < 1, a power <= 0 or a negative cache size.
    """

    def __init__(self, capacity: int, power: float = 2.0, render: Renderer | None = None,
                 cache_size: int = DEFAULT_CACHE) -> None:
        if capacity < 1:
            raise ConfigError("agent.replay_capacity", f"must be >= 1, got {capacity}")
        if not (np.isfinite(power) and power > 0):
            raise ConfigError("replay.power", f"must be > 0, got {power!r}")
        if cache_size < 0:
            raise ConfigError("replay.cache_size", f"must be >= 0, got {cache_size}")
        self.capacity = int(capacity)
        self.power = float(power)
        self.render = render
        self.cache_size = int(cache_size)
        self._cache: OrderedDict[int, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self.renders = 0  # maps rendered by get() (cache misses)
        self.cache_hits = 0
        self._size = 0
        self._cursor = 0
        self._count = 0
        self._a: dict[str, np.ndarray | None] = dict.fromkeys(self._names)

    @property
    def keeps_scenes(self) -> bool:
        """True if the buffer keeps scene seeds and re-renders the maps."""
        return self.render is not None

    @property
    def _names(self) -> tuple[str, ...]:
        return _SCENE_ARRAYS if self.keeps_scenes else _MAP_ARRAYS

    def __len__(self) -> int:
        return self._size

    def _allocate(self, t: Transition) -> None:
        n = self.capacity
        if self.keeps_scenes:
            self._a["scene"] = np.zeros(n, np.int64)
        else:
            self._a.update(color=np.zeros((n, *t.color.shape), np.uint8),
                           depth=np.zeros((n, *t.depth.shape), np.float32))
        self._a.update(
            has_next=np.zeros(n, bool),
            action=np.zeros((n, 3), np.int64),
            reward=np.zeros(n, np.float64),
            done=np.zeros(n, bool),
            surprise=np.zeros(n, np.float64),
            serial=np.zeros(n, np.int64),
        )

    def add(self, transition: Transition, surprise: float) -> int:
        """Store a transition with its surprise |TD error|; returns its slot index.

        A scene-keyed buffer keeps the transition's scene seed, and its maps in the cache.

        Raises:
            ConfigError: If the heightmap size differs from the stored ones or the surprise is
                negative or not finite; for a scene-keyed buffer, if the transition has no
                scene seed or has a next state.
        """
        if not (np.isfinite(surprise) and surprise >= 0):
            raise ConfigError("replay.surprise", f"must be a finite value >= 0, got {surprise!r}")
        if self.keeps_scenes:
            if transition.scene is None:
                raise ConfigError("replay.transition", "has no scene seed; a scene-keyed buffer "
                                                       "re-renders the maps from it")
            if transition.has_next:
                raise ConfigError("replay.transition", "has a next state; a scene-keyed buffer "
                                                       "keeps terminal transitions only")
            return self._add_scene(transition, surprise)
        a = self._a
        if a["color"] is None:
            self._allocate(transition)
        elif transition.color.shape != a["color"].shape[1:]:
            raise ConfigError(
                "replay.transition",
                f"heightmap {transition.color.shape[:2]} differs from the stored "
                f"{a['color'].shape[1:3]}",
            )
        if transition.has_next and a["next_color"] is None:
            a["next_color"] = np.zeros_like(a["color"])
            a["next_depth"] = np.zeros_like(a["depth"])
        i = self._cursor
        a["color"][i] = transition.color
        a["depth"][i] = transition.depth
        a["has_next"][i] = transition.has_next
        if transition.has_next:
            a["next_color"][i] = transition.next_color
            a["next_depth"][i] = transition.next_depth
        return self._add_common(transition, surprise)

    def _add_scene(self, transition: Transition, surprise: float) -> int:
        if self._a["scene"] is None:
            self._allocate(transition)
        i = self._cursor
        self._a["scene"][i] = int(transition.scene)
        self._a["has_next"][i] = False
        self._remember(int(transition.scene), transition.color, transition.depth)
        return self._add_common(transition, surprise)

    def _add_common(self, transition: Transition, surprise: float) -> int:
        a = self._a
        i = self._cursor
        a["action"][i] = [int(v) for v in transition.action]
        a["reward"][i] = transition.reward
        a["done"][i] = transition.done
        a["surprise"][i] = surprise
        a["serial"][i] = self._count
        self._count += 1
        self._cursor = (i + 1) % self.capacity
        self._size = min(self._size + 1, self.capacity)
        return i

    def _remember(self, scene: int, color: np.ndarray, depth: np.ndarray) -> None:
        if self.cache_size == 0:
            return
        self._cache[scene] = (np.array(color, copy=True), np.array(depth, copy=True))
        self._cache.move_to_end(scene)
        while len(self._cache) > self.cache_size:
            self._cache.popitem(last=False)

    def maps(self, scene: int) -> tuple[np.ndarray, np.ndarray]:
        """The heightmaps of a scene seed (scene-keyed buffer): from the cache, else rendered.

        Returns:
            Copies ``(color, depth)``.

        Raises:
            ConfigError: If the buffer keeps maps, or the renderer gives something other than
                uint8 (H, W, 3) colour and (H, W) depth.
        """
        if self.render is None:
            raise ConfigError("replay.render", "this buffer keeps maps, not scenes")
        scene = int(scene)
        if scene in self._cache:
            self.cache_hits += 1
            self._cache.move_to_end(scene)
            color, depth = self._cache[scene]
        else:
            self.renders += 1
            color, depth = self.render(scene)
            color = np.asarray(color)
            depth = np.asarray(depth, dtype=np.float32)
            if color.dtype != np.uint8 or color.ndim != 3 or depth.shape != color.shape[:2]:
                raise ConfigError("replay.render", f"scene {scene} rendered as {color.dtype} "
                                                   f"{color.shape} and {depth.shape}")
            self._remember(scene, color, depth)
        return color.copy(), depth.copy()

    def scene(self, index: int) -> int:
        """Scene seed of slot ``index`` (scene-keyed buffer).

        Raises:
            ConfigError: If the slot is empty or the buffer keeps maps.
        """
        self._check_index(index)
        if not self.keeps_scenes:
            raise ConfigError("replay.scene", "this buffer keeps maps, not scenes")
        return int(self._a["scene"][index])

    def newest(self) -> int | None:
        """Slot of the most recently added transition, or ``None`` when empty."""
        return None if self._size == 0 else (self._cursor - 1) % self.capacity

    def get(self, index: int) -> Transition:
        """The transition in slot ``index`` (copies of the stored arrays; a scene-keyed buffer
        re-renders its maps, or takes them from the cache).

        Raises:
            ConfigError: If the slot is empty.
        """
        self._check_index(index)
        a = self._a
        if self.keeps_scenes:
            scene = int(a["scene"][index])
            color, depth = self.maps(scene)
            return Transition(color=color, depth=depth,
                              action=tuple(int(v) for v in a["action"][index]),
                              reward=float(a["reward"][index]), done=bool(a["done"][index]),
                              scene=scene)
        has_next = bool(a["has_next"][index])
        return Transition(
            color=a["color"][index].copy(),
            depth=a["depth"][index].copy(),
            action=tuple(int(v) for v in a["action"][index]),
            reward=float(a["reward"][index]),
            next_color=a["next_color"][index].copy() if has_next else None,
            next_depth=a["next_depth"][index].copy() if has_next else None,
            done=bool(a["done"][index]),
        )

    def surprise(self, index: int) -> float:
        """Stored surprise of slot ``index``."""
        self._check_index(index)
        return float(self._a["surprise"][index])

    def _check_index(self, index: int) -> None:
        if not 0 <= index < self._size:
            raise ConfigError("replay.index", f"slot {index} is empty (size {self._size})")

    def update_surprise(self, index: int, surprise: float) -> None:
        """Replace the surprise of slot ``index`` (after replaying it).

        Raises:
            ConfigError: On an empty slot or a negative or non-finite surprise.
        """
        self._check_index(index)
        if not (np.isfinite(surprise) and surprise >= 0):
            raise ConfigError("replay.surprise", f"must be a finite value >= 0, got {surprise!r}")
        self._a["surprise"][index] = surprise

    def ranked(self, exclude_reward: float | None = None) -> np.ndarray:
        """Candidate slot indices sorted by surprise, ascending (ties: oldest first).

        Args:
            exclude_reward: Leave out transitions with exactly this reward (VPG replays
                transitions whose reward differs from the latest one).
        """
        idx = np.arange(self._size)
        if self._size and exclude_reward is not None:
            idx = idx[self._a["reward"][: self._size] != exclude_reward]
        if idx.size == 0:
            return idx
        order = np.lexsort((self._a["serial"][idx], self._a["surprise"][idx]))
        return idx[order]

    def sample_index(
        self, rng: np.random.Generator, exclude_reward: float | None = None
    ) -> int | None:
        """Draw one slot by surprise rank with the power law (module docstring).

        Returns:
            A slot index, or ``None`` when there is no candidate.
        """
        ranked = self.ranked(exclude_reward)
        if ranked.size == 0:
            return None
        u = float(rng.power(self.power))
        return int(ranked[int(round(u * (ranked.size - 1)))])

    def sample(
        self, rng: np.random.Generator, exclude_reward: float | None = None
    ) -> tuple[int, Transition] | None:
        """Draw one transition by surprise rank; returns ``(slot, transition)`` or ``None``."""
        index = self.sample_index(rng, exclude_reward)
        return None if index is None else (index, self.get(index))

    def rank_probabilities(self, n: int) -> np.ndarray:
        """Exact probabilities P(i), i = 0..n-1, of drawing rank position i (0 = least surprise).

        P(i) = F((i + 1/2) / (n - 1)) - F((i - 1/2) / (n - 1)) with F(x) = clip(x, 0, 1)^a;
        for n = 1 the single transition has probability 1.
        """
        if n < 1:
            raise ConfigError("replay.n", f"must be >= 1, got {n}")
        if n == 1:
            return np.ones(1)
        i = np.arange(n, dtype=np.float64)
        upper = np.clip((i + 0.5) / (n - 1), 0.0, 1.0) ** self.power
        lower = np.clip((i - 0.5) / (n - 1), 0.0, 1.0) ** self.power
        return upper - lower

    def state_dict(self) -> dict[str, Any]:
        """Picklable state: scalars and numpy arrays of the occupied slots (views, not copies).

        The arrays of a scene-keyed buffer are ``scene`` and the per-transition scalars (no
        maps, no cache); those of a map buffer hold the maps."""
        n = self._size
        arrays = {k: (None if v is None else v[:n]) for k, v in self._a.items()}
        return {
            "capacity": self.capacity,
            "power": self.power,
            "size": n,
            "cursor": self._cursor,
            "count": self._count,
            "arrays": arrays,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict` (same capacity, same kind: scenes or maps).

        Raises:
            ConfigError: On a capacity mismatch, missing entries or the other kind's arrays.
        """
        missing = {"capacity", "power", "size", "cursor", "count", "arrays"} - set(state)
        if missing:
            raise ConfigError("replay.state", f"missing entries {sorted(missing)}")
        if int(state["capacity"]) != self.capacity:
            raise ConfigError(
                "agent.replay_capacity",
                f"checkpoint capacity {state['capacity']} != buffer capacity {self.capacity}",
            )
        size = int(state["size"])
        arrays = state["arrays"]
        names = self._names
        if set(arrays) != set(names):
            kind = "scenes" if self.keeps_scenes else "maps"
            raise ConfigError("replay.state", f"array names {sorted(arrays)} != {list(names)} "
                                              f"(this buffer keeps {kind})")
        self.power = float(state["power"])
        self._size, self._cursor, self._count = size, int(state["cursor"]), int(state["count"])
        self._a = dict.fromkeys(names)
        self._cache.clear()
        if arrays[names[0]] is None:
            return
        for name, value in arrays.items():
            if value is None:
                continue
            value = np.asarray(value)
            if value.shape[0] != size:
                raise ConfigError("replay.state", f"array {name} holds {value.shape[0]} != {size}")
            full = np.zeros((self.capacity, *value.shape[1:]), value.dtype)
            full[:size] = value
            self._a[name] = full


__all__ = ["DEFAULT_CACHE", "ReplayBuffer", "Renderer", "Transition", "maps_digest"]
