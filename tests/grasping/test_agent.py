"""Grasp agent: network, loss locality, TD targets, actions, schedule, checkpoints."""

from __future__ import annotations

import io

import numpy as np
import pytest
import torch

from vgs.config import AgentConfig, NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.agent import (
    DeltaQMonitor,
    GraspAgent,
    epsilon_schedule,
    opposite_rotation,
    td_loss,
)
from vgs.grasping.replay import ReplayBuffer, Transition

NET = NetworkConfig(
        action="rotation", backbone="light", num_rotations=4)


def _agent(seed: int = 0, **agent_kw: float) -> GraspAgent:
    return GraspAgent(NET, AgentConfig(**agent_kw), seed=seed)


def _maps(seed: int, size: int = 24) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    color = rng.integers(0, 256, (size, size, 3), dtype=np.uint8)
    depth = np.zeros((size, size), np.float32)
    depth[8:14, 5:19] = 0.03
    return color, depth


def _params(net: torch.nn.Module) -> list[torch.Tensor]:
    return [t.detach().clone() for t in net.state_dict().values()]


def _same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


def test_networks_start_seeded() -> None:
    a, b, c = _agent(0), _agent(0), _agent(1)
    assert _same(_params(a.eva_net), _params(b.eva_net))
    assert not _same(_params(a.eva_net), _params(c.eva_net))
    group = a.optimizer.param_groups[0]
    assert (group["lr"], group["momentum"], group["weight_decay"]) == (1e-4, 0.9, 2e-5)


def test_opposite_rotation() -> None:
    assert opposite_rotation(0, 16) == 8 and opposite_rotation(11, 16) == 3
    assert opposite_rotation(0, 1) is None and opposite_rotation(2, 5) is None


def test_td_loss_values_and_locality() -> None:
    q = torch.zeros(4, 6, 7, requires_grad=True)
    with torch.no_grad():
        q[0, 2, 3] = 0.5
        q[2, 2, 3] = 3.0
    loss = td_loss(q, [0, 2], 2, 3, 1.0)
    # 0.5 * 0.5^2 (|x| < 1)  +  |3 - 1| - 0.5 (|x| >= 1)
    assert float(loss.detach()) == pytest.approx(0.125 + 1.5)
    loss.backward()
    nonzero = torch.nonzero(q.grad).tolist()
    assert nonzero == [[0, 2, 3], [2, 2, 3]]
    assert q.grad[0, 2, 3] == pytest.approx(-0.5) and q.grad[2, 2, 3] == pytest.approx(1.0)


def test_update_gradient_only_at_executed_pixel() -> None:
    agent = _agent(learning_rate=0.01)
    captured: dict[str, torch.Tensor] = {}

    def hook(_module: torch.nn.Module, _inputs: object, output: torch.Tensor) -> None:
        output.retain_grad()
        captured["q"] = output

    handle = agent.eva_net.register_forward_hook(hook)
    color, depth = _maps(0)
    stats = agent.update(Transition(color, depth, (1, 9, 12), 1.0))
    handle.remove()
    grad = captured["q"].grad  # (1, 2, H, W): rotations 1 and its opposite 3
    assert grad.shape == (1, 2, 24, 24)
    assert torch.nonzero(grad).tolist() == [[0, 0, 9, 12], [0, 1, 9, 12]]
    assert stats["delta_q"] == pytest.approx(abs(stats["target"] - stats["q_eva"]))
    assert stats["target"] == 1.0
    assert set(stats) == {"loss", "delta_q", "q_eva", "target"}


def test_the_target_is_the_reward_of_a_terminal_transition() -> None:
    agent = _agent()
    color, depth = _maps(1)
    n_color, n_depth = _maps(2)
    assert agent.target_value(Transition(color, depth, (0, 3, 3), 0.3)) == 0.3
    stored_next = Transition(color, depth, (0, 3, 3), 0.3, n_color, n_depth, done=True)
    assert agent.update(stored_next)["target"] == 0.3
    with pytest.raises(ConfigError, match="transition.done"):
        agent.update(Transition(color, depth, (0, 3, 3), 0.3, n_color, n_depth, done=False))
    assert agent.updates == 1


def test_act_greedy_and_exploratory() -> None:
    agent = _agent()
    color, depth = _maps(4)
    mask = depth > 0.005
    rng = np.random.default_rng(0)
    greedy = agent.act(color, depth, 0.0, mask, rng)
    q = agent.q_values(color, depth)
    assert greedy.q_map.shape == (4, 24, 24)
    masked = np.where(mask[None], q, -np.inf)
    assert greedy.action == tuple(np.unravel_index(np.argmax(masked), q.shape))
    assert not greedy.explored and greedy.q_value == pytest.approx(masked.max())
    assert greedy.angle == pytest.approx(greedy.rotation * np.pi / 2)
    # empty mask: every pixel is allowed
    free = agent.act(color, depth, 0.0, np.zeros_like(mask), rng)
    assert free.action == tuple(np.unravel_index(np.argmax(q), q.shape))
    # exploration: valid pixels, all rotations
    picks = [agent.act(color, depth, 1.0, mask, rng, skip_q_if_exploring=True)
             for _ in range(40)]
    assert all(p.explored and mask[p.row, p.col] and p.q_map is None for p in picks)
    assert {p.rotation for p in picks} == {0, 1, 2, 3}
    with pytest.raises(ConfigError):
        agent.act(color, depth, 1.5, mask, rng)
    with pytest.raises(ConfigError):
        agent.act(color, depth, 0.5, mask[:5], rng)


def test_act_uses_eval_mode_batchnorm() -> None:
    agent = _agent()
    color, depth = _maps(5)
    agent.eva_net.train()
    before = {k: v.clone() for k, v in agent.eva_net.state_dict().items() if "running" in k}
    agent.act(color, depth, 0.0, None, np.random.default_rng(0))
    after = {k: v for k, v in agent.eva_net.state_dict().items() if "running" in k}
    assert all(torch.equal(before[k], after[k]) for k in before)  # no BN statistics update


def test_epsilon_schedule() -> None:
    cfg = AgentConfig(random_episodes=10, epsilon_start=0.5, epsilon_end=0.1)
    assert epsilon_schedule(0, 31, cfg) == 1.0
    assert epsilon_schedule(9, 31, cfg) == 1.0
    assert epsilon_schedule(10, 31, cfg) == pytest.approx(0.5)
    assert epsilon_schedule(20, 31, cfg) == pytest.approx(0.3)
    assert epsilon_schedule(30, 31, cfg) == pytest.approx(0.1)
    assert epsilon_schedule(100, 31, cfg) == pytest.approx(0.1)
    paper = AgentConfig()
    assert epsilon_schedule(999, 5000, paper) == 1.0
    assert epsilon_schedule(1000, 5000, paper) == pytest.approx(0.5)
    assert epsilon_schedule(4999, 5000, paper) == pytest.approx(0.1)
    assert _agent().epsilon(3000, 5000) == pytest.approx(0.5 - 0.4 * 2000 / 3999)
    with pytest.raises(ConfigError):
        epsilon_schedule(-1, 10, cfg)


def test_replay_update_refreshes_surprise() -> None:
    agent = _agent(learning_rate=0.01, replay_batch=3)
    buf = ReplayBuffer(8)
    for i in range(4):
        color, depth = _maps(10 + i)
        buf.add(Transition(color, depth, (i, 9, 9), float(i % 2)), 10.0 + i)
    results = agent.replay_update(buf, np.random.default_rng(0))
    assert len(results) == 3 and agent.updates == 3
    latest = {int(r["index"]): r["delta_q"] for r in results}  # a slot may be drawn twice
    for index, delta_q in latest.items():
        assert buf.surprise(index) == pytest.approx(delta_q)
        assert delta_q < 10.0
    assert agent.replay_update(ReplayBuffer(2), np.random.default_rng(0)) == []


def test_state_dict_round_trip() -> None:
    agent = _agent(learning_rate=0.01)
    color, depth = _maps(6)
    for k in range(3):
        agent.update(Transition(color, depth, (k, 4, 4), 1.0))
    buffer = io.BytesIO()
    torch.save(agent.state_dict(), buffer)
    buffer.seek(0)
    other = _agent(seed=7, learning_rate=0.01)
    other.load_state_dict(torch.load(buffer, weights_only=True))
    assert other.updates == 3
    np.testing.assert_array_equal(agent.q_values(color, depth), other.q_values(color, depth))
    # identical next step, momentum buffers included
    t = Transition(color, depth, (1, 5, 6), 0.0)
    assert agent.update(t) == other.update(t)
    wrong = GraspAgent(NetworkConfig(
        action="rotation", backbone="light", num_rotations=8), AgentConfig())
    with pytest.raises(ConfigError):
        wrong.load_state_dict(agent.state_dict())


def test_a_state_written_with_a_target_network_loads() -> None:
    """States saved before the target network was removed carry a ``target_net`` entry."""
    agent = _agent(learning_rate=0.01)
    color, depth = _maps(6)
    agent.update(Transition(color, depth, (1, 4, 4), 1.0))
    old = {**agent.state_dict(), "target_net": _agent(seed=3).eva_net.state_dict()}
    other = _agent(seed=7, learning_rate=0.01)
    other.load_state_dict(old)
    assert other.updates == 1
    np.testing.assert_array_equal(agent.q_values(color, depth), other.q_values(color, depth))


def test_delta_q_monitor() -> None:
    mon = DeltaQMonitor(0.1, 3)
    assert not mon.update(0.05) and not mon.update(0.05)
    assert mon.update(0.05)
    assert not mon.update(0.2)  # one large value in the window
    assert not mon.update(0.01) and not mon.update(0.01)
    assert mon.update(0.01)
    assert mon.mean == pytest.approx(0.01)
    clone = DeltaQMonitor.from_config(AgentConfig())
    clone.load_state_dict(mon.state_dict())
    assert clone.converged and clone.window == 3
    with pytest.raises(ConfigError):
        DeltaQMonitor(0.0, 3)


def test_bfloat16_precision_q_values_and_update() -> None:
    """bfloat16 autocast: float32 Q maps within bfloat16 rounding of the float32 ones (same
    weights), float32 weights after an update, a finite loss."""
    color, depth = _maps(0)
    exact = _agent(seed=3)
    fast = GraspAgent(NetworkConfig(
        action="rotation", backbone="light", num_rotations=4, precision="bfloat16"),
                      AgentConfig(), seed=3)
    assert _same(_params(exact.eva_net), _params(fast.eva_net))
    q32, q16 = exact.q_values(color, depth), fast.q_values(color, depth)
    assert q16.dtype == np.float32
    assert not np.array_equal(q32, q16)  # the forward pass did run in bfloat16
    scale = float(np.abs(q32).max())
    assert float(np.abs(q32 - q16).max()) < 0.05 * scale
    stats = fast.update(Transition(color, depth, (1, 10, 10), 1.0))
    assert np.isfinite(stats["loss"])
    assert all(p.dtype == torch.float32 for p in fast.eva_net.parameters())


def test_precision_is_checked() -> None:
    with pytest.raises(ConfigError, match="network.precision"):
        NetworkConfig(precision="float16")
