"""The paper's position action on a synthetic heightmap with a known answer: a chosen pixel
becomes a grasp at that point, the jaws closing across the peg's axis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vgs.assembly.episode import center_policy, peg_axis_from_heightmap
from vgs.config import AgentConfig, NetworkConfig, profile
from vgs.grasping.actions import closing_angle, peg_mask, perceived_jaw_angle
from vgs.grasping.agent import GraspAgent
from vgs.rollout.policies import RandomPolicy, pixel_command
from vgs.sim.camera import Heightmap

SIZE, PIXEL = 96, 0.002  # 96 px of 2 mm


def bar_heightmap(phi: float, length: float = 0.1, width: float = 0.028) -> Heightmap:
    """A lying peg of ``length`` x ``width`` [m], 30 mm high, its axis at ``phi`` [rad] from
    world +x, centred on the map (the width is not a whole number of pixels, so no pixel centre
    lies on its edge and the raster stays symmetric)."""
    rows, cols = np.mgrid[0:SIZE, 0:SIZE]
    x, y = (cols + 0.5) * PIXEL - SIZE * PIXEL / 2, (rows + 0.5) * PIXEL - SIZE * PIXEL / 2
    u = x * math.cos(phi) + y * math.sin(phi)
    v = -x * math.sin(phi) + y * math.cos(phi)
    bar = (np.abs(u) < length / 2) & (np.abs(v) < width / 2)
    depth = np.where(bar, 0.03, 0.0).astype(np.float32)
    color = np.full((SIZE, SIZE, 3), 60, np.uint8)
    color[bar] = (200, 40, 40)
    return Heightmap(color, depth, (-SIZE * PIXEL / 2, -SIZE * PIXEL / 2), PIXEL)


def folded_deg(a: float, b: float) -> float:
    """Angle between two undirected directions [deg], in [0, 90]."""
    return abs((math.degrees(a - b) + 90.0) % 180.0 - 90.0)


@pytest.mark.parametrize("phi_deg", [0.0, 23.0, 90.0, 137.0, -61.0])
def test_a_chosen_pixel_is_a_grasp_there_with_the_jaws_across_the_axis(phi_deg: float) -> None:
    phi = math.radians(phi_deg)
    hm = bar_heightmap(phi)
    network = profile("paper-light").network
    assert network.action == "position"
    row, col = SIZE // 2 + 5, SIZE // 2 - 3  # a peg pixel off the centre
    assert peg_mask(hm.depth)[row, col]
    command = pixel_command(hm, row, col, closing_angle(network.action, 0,
                                                        network.num_rotations, hm.depth))
    assert (command.x, command.y) == pytest.approx(hm.pixel_to_world(row, col))
    # The pads' long side lies along the peg's axis: the jaws close across it.
    assert folded_deg(command.yaw, phi) < 1.0
    closing = perceived_jaw_angle(hm.depth)
    assert folded_deg(closing, phi + math.pi / 2) < 1.0
    # The same perception as the centre heuristic's.
    _, axis, _ = peg_axis_from_heightmap(hm)
    assert folded_deg(command.yaw, center_policy()(hm).yaw) < 1e-6
    assert folded_deg(command.yaw, math.atan2(axis[1], axis[0])) < 1e-6


def test_random_and_greedy_position_actions_close_across_the_axis() -> None:
    phi = math.radians(33.0)
    hm = bar_heightmap(phi)
    cfg = profile("smoke")
    assert cfg.network.action == "position"
    rng = np.random.default_rng(0)
    for _ in range(10):
        decision = RandomPolicy(cfg.network)(hm, rng)
        assert peg_mask(hm.depth)[decision.row, decision.col]
        assert folded_deg(decision.command.yaw, phi) < 1.0
    agent = GraspAgent(NetworkConfig(backbone="light"), AgentConfig(), seed=0)
    action = agent.act(hm.color, hm.depth, 0.0, peg_mask(hm.depth), rng)
    assert action.q_map is not None and action.q_map.shape == (1, SIZE, SIZE)
    assert action.rotation == 0 and peg_mask(hm.depth)[action.row, action.col]
    assert action.angle == pytest.approx(perceived_jaw_angle(hm.depth))


@pytest.mark.parametrize("rotate", ["input", "none"])
def test_the_network_sees_the_map_turned_by_its_own_perceived_angle(rotate: str) -> None:
    """rotate=input turns each map by its perceived jaw angle before the trunks (so another
    angle gives another Q map); rotate=none sees the map as captured."""
    import torch

    from vgs.grasping.preprocess import preprocess

    agent = GraspAgent(NetworkConfig(backbone="light", rotate=rotate), AgentConfig(), seed=0)
    hm = bar_heightmap(math.radians(33.0))
    q = agent.q_values(hm.color, hm.depth)[0]
    c, d = preprocess(hm.color, hm.depth, agent.network_cfg)
    agent.eva_net.eval()
    with torch.inference_mode():
        own = agent.eva_net(c, d, angles=[perceived_jaw_angle(hm.depth)])[0, 0].numpy()
        other = agent.eva_net(c, d, angles=[0.3])[0, 0].numpy()
    np.testing.assert_allclose(q, own, rtol=1e-5, atol=1e-6)
    assert (np.abs(q - other).max() > 1e-3) == (rotate == "input")
