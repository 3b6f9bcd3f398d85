"""Prioritised replay: ranking, power-law sampling, eviction, checkpoints."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from vgs.errors import ConfigError
from vgs.grasping.replay import (
    CACHE_BYTES,
    DEFAULT_CACHE,
    ReplayBuffer,
    Transition,
    cache_size_for,
)


def _transition(i: int, reward: float = 0.0, with_next: bool = False) -> Transition:
    color = np.full((6, 5, 3), i % 256, np.uint8)
    depth = np.full((6, 5), 0.001 * i, np.float32)
    nxt = (color + 1, depth + 1.0) if with_next else (None, None)
    return Transition(color, depth, (i % 4, i % 6, i % 5), reward, nxt[0], nxt[1],
                      done=not with_next)


def test_ranking_by_surprise() -> None:
    buf = ReplayBuffer(10)
    for i, s in enumerate([0.5, 0.1, 0.9, 0.1, 0.3]):
        buf.add(_transition(i), s)
    # ascending surprise; the tie (slots 1 and 3) goes to the older one first
    assert buf.ranked().tolist() == [1, 3, 4, 0, 2]
    buf.update_surprise(2, 0.0)
    assert buf.ranked().tolist() == [2, 1, 3, 4, 0]
    assert buf.surprise(2) == 0.0


def test_power_law_sampling_frequencies() -> None:
    buf = ReplayBuffer(10)
    for i in range(5):
        buf.add(_transition(i), float(i))  # slot i has rank i
    p = buf.rank_probabilities(5)
    np.testing.assert_allclose(p, [1 / 64, 8 / 64, 16 / 64, 24 / 64, 15 / 64])
    assert p.sum() == pytest.approx(1.0)
    rng = np.random.default_rng(0)
    draws = np.array([buf.sample_index(rng) for _ in range(20000)])
    freq = np.bincount(draws, minlength=5) / draws.size
    np.testing.assert_allclose(freq, p, atol=0.015)
    # uniform with power 1
    flat = ReplayBuffer(10, power=1.0)
    np.testing.assert_allclose(flat.rank_probabilities(5), [1 / 8, 1 / 4, 1 / 4, 1 / 4, 1 / 8])


def test_sample_returns_transition_and_exclusion() -> None:
    buf = ReplayBuffer(10)
    rng = np.random.default_rng(1)
    assert buf.sample(rng) is None
    buf.add(_transition(0, reward=1.0), 0.2)
    buf.add(_transition(1, reward=0.0), 0.9)
    for _ in range(20):
        index, t = buf.sample(rng, exclude_reward=0.0)
        assert index == 0 and t.reward == 1.0 and t.action == (0, 0, 0)
    assert buf.sample(rng, exclude_reward=5.0) is not None
    assert ReplayBuffer(3).sample_index(rng) is None


def test_eviction_of_the_oldest() -> None:
    buf = ReplayBuffer(3)
    for i in range(5):
        buf.add(_transition(i), 1.0)
    assert len(buf) == 3
    stored = sorted(int(buf.get(j).color[0, 0, 0]) for j in range(3))
    assert stored == [2, 3, 4]
    with pytest.raises(ConfigError):
        buf.get(5)


def test_next_state_storage() -> None:
    buf = ReplayBuffer(4)
    buf.add(_transition(1), 0.1)
    buf.add(_transition(2, with_next=True), 0.1)
    assert buf.get(0).next_color is None and buf.get(0).done
    t = buf.get(1)
    assert t.has_next and not t.done
    np.testing.assert_array_equal(t.next_color, _transition(2).color + 1)


def test_state_dict_round_trip() -> None:
    buf = ReplayBuffer(4)
    for i in range(6):
        buf.add(_transition(i, reward=float(i % 2), with_next=i == 5), 0.1 * i)
    blob = pickle.dumps(buf.state_dict())
    other = ReplayBuffer(4)
    other.load_state_dict(pickle.loads(blob))
    assert len(other) == 4
    assert other.ranked().tolist() == buf.ranked().tolist()
    for j in range(4):
        a, b = buf.get(j), other.get(j)
        np.testing.assert_array_equal(a.color, b.color)
        np.testing.assert_array_equal(a.depth, b.depth)
        assert (a.action, a.reward, a.done, a.has_next) == (b.action, b.reward, b.done, b.has_next)
    # the ring cursor continues where it was: the next add evicts the same (oldest) slot
    assert buf.add(_transition(9), 0.0) == other.add(_transition(9), 0.0)
    with pytest.raises(ConfigError):
        ReplayBuffer(5).load_state_dict(buf.state_dict())


def test_errors() -> None:
    with pytest.raises(ConfigError):
        ReplayBuffer(0)
    buf = ReplayBuffer(2)
    with pytest.raises(ConfigError):
        buf.add(_transition(0), -1.0)
    buf.add(_transition(0), 0.0)
    bad = Transition(np.zeros((3, 3, 3), np.uint8), np.zeros((3, 3), np.float32), (0, 0, 0), 0.0)
    with pytest.raises(ConfigError):
        buf.add(bad, 0.0)
    with pytest.raises(ConfigError):
        Transition(np.zeros((3, 3, 3), np.uint8), np.zeros((3, 3), np.float32), (0, 3, 0), 0.0)


# -- scene-keyed buffer: seeds in, heightmaps re-rendered -----------------------------------------


class Scenes:
    """A renderer whose maps depend on the seed only, counting its calls."""

    def __init__(self) -> None:
        self.calls: list[int] = []

    def __call__(self, scene: int) -> tuple[np.ndarray, np.ndarray]:
        self.calls.append(scene)
        rng = np.random.default_rng(scene)
        return (rng.integers(0, 256, (6, 5, 3), dtype=np.uint8),
                rng.uniform(0, 0.05, (6, 5)).astype(np.float32))


def _scene_transition(scene: int, reward: float = 0.0) -> Transition:
    color, depth = Scenes()(scene)
    return Transition(color, depth, (scene % 4, scene % 6, scene % 5), reward, scene=scene)


def test_a_scene_buffer_keeps_seeds_and_re_renders_the_maps() -> None:
    render = Scenes()
    buf = ReplayBuffer(4, render=render, cache_size=2)
    for s in (10, 11, 12):
        buf.add(_scene_transition(s, reward=float(s % 2)), 0.1 * s)
    state = buf.state_dict()
    assert set(state["arrays"]) == {"scene", "has_next", "action", "reward", "done", "surprise",
                                    "serial"}
    assert state["arrays"]["scene"].tolist() == [10, 11, 12]
    assert render.calls == []  # added maps are cached, never rendered
    t = buf.get(0)  # scene 10 left the 2-map cache
    assert render.calls == [10] and (buf.renders, buf.cache_hits) == (1, 0)
    want = _scene_transition(10, reward=0.0)
    np.testing.assert_array_equal(t.color, want.color)
    assert t.depth.tobytes() == want.depth.tobytes()
    assert (t.action, t.reward, t.done, t.scene) == (want.action, 0.0, True, 10)
    buf.get(0)
    buf.get(2)
    assert render.calls == [10] and buf.cache_hits == 2
    assert buf.scene(1) == 11 and buf.newest() == 2
    # a restored buffer holds no maps and renders what it reads
    other = ReplayBuffer(4, render=Scenes(), cache_size=0)
    other.load_state_dict(pickle.loads(pickle.dumps(state)))
    assert other.ranked().tolist() == buf.ranked().tolist()
    for j in range(3):
        np.testing.assert_array_equal(other.get(j).color, buf.get(j).color)
    assert other.render.calls == [10, 11, 12]


def test_a_scene_buffer_refuses_what_it_cannot_re_render() -> None:
    buf = ReplayBuffer(4, render=Scenes())
    plain = _transition(1)
    with pytest.raises(ConfigError, match="scene seed"):
        buf.add(plain, 0.0)
    with_next = Transition(plain.color, plain.depth, plain.action, 0.0, plain.color,
                           plain.depth, done=False, scene=3)
    with pytest.raises(ConfigError, match="next state"):
        buf.add(with_next, 0.0)
    maps = ReplayBuffer(4)
    maps.add(plain, 0.0)
    with pytest.raises(ConfigError, match="keeps scenes"):
        buf.load_state_dict(maps.state_dict())
    with pytest.raises(ConfigError, match="keeps maps"):
        maps.maps(3)
    with pytest.raises(ConfigError):
        ReplayBuffer(4, render=Scenes(), cache_size=-1)


def test_training_caches_a_whole_paper_light_buffer_within_its_memory_budget() -> None:
    """The cache's size only trades memory for renders (replays return the same maps)."""
    per_map = 3 * 224 * 224 + 4 * 224 * 224  # uint8 colour, float32 depth: 351 kB
    assert cache_size_for(5000, 224) == 5000  # 1.76 GB, inside the 2 GiB budget
    assert cache_size_for(20_000, 224) == CACHE_BYTES // per_map < 20_000
    assert cache_size_for(5000, 224, budget=0) == DEFAULT_CACHE
    render = Scenes()
    buf = ReplayBuffer(6, render=render, cache_size=cache_size_for(6, 5))
    for s in range(6):
        buf.add(_scene_transition(s), 0.1)
    for j in range(6):
        buf.get(j)
    assert render.calls == [] and buf.cache_hits == 6
