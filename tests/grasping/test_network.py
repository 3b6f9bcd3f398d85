"""Grasp Q network: shapes, rotation geometry, rotation subsets, model_info."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from vgs.config import NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.light import LightTrunk
from vgs.grasping.network import (
    GraspQNetwork,
    format_model_info,
    jaw_axis,
    model_info,
    padded_size,
    rotate_images,
    rotation_angle,
)


def _light(num_rotations: int = 4, rotate: str = "input", seed: int = 0) -> GraspQNetwork:
    torch.manual_seed(seed)
    return GraspQNetwork(NetworkConfig(
        action="rotation", backbone="light", num_rotations=num_rotations),
                         rotate=rotate).eval()


def _smooth_image(size: int, channels: int = 3) -> torch.Tensor:
    y, x = torch.meshgrid(torch.linspace(-1, 1, size), torch.linspace(-1, 1, size),
                          indexing="ij")
    maps = [torch.sin(2.0 * x + c) * torch.cos(1.5 * y - c) + 0.3 * x * y
            for c in range(channels)]
    return torch.stack(maps)[None]


def test_padded_size() -> None:
    assert padded_size(224, 224) == 320  # ceil(224 sqrt 2) = 317 -> 320
    assert padded_size(32, 32) == 64
    assert padded_size(48, 48) == 96
    assert padded_size(32, 40) == 64  # ceil(sqrt(32^2 + 40^2)) = 52


def test_rotation_angles() -> None:
    assert rotation_angle(0, 16) == 0.0
    assert rotation_angle(4, 16) == pytest.approx(math.pi / 2)
    assert rotation_angle(15, 16) == pytest.approx(2 * math.pi * 15 / 16)
    assert _light(8).rotation_angle(2) == pytest.approx(math.pi / 2)
    with pytest.raises(ConfigError):
        rotation_angle(16, 16)


def test_light_trunk_shape() -> None:
    trunk = LightTrunk().eval()
    assert trunk(torch.randn(2, 3, 64, 48)).shape == (2, 128, 8, 6)
    assert 200_000 < sum(p.numel() for p in trunk.parameters()) < 400_000


@pytest.mark.parametrize("rotate", ["input", "features"])
def test_output_shape_light(rotate: str) -> None:
    net = _light(4, rotate)
    color, depth = torch.randn(2, 3, 32, 40), torch.randn(2, 3, 32, 40)
    with torch.no_grad():
        q = net(color, depth)
        sub = net(color, depth, rotations=[3, 1])
    assert q.shape == (2, 4, 32, 40)
    torch.testing.assert_close(sub, q[:, [3, 1]])
    # Different orientations must give different maps (in both modes).
    assert (q[:, 0] - q[:, 1]).abs().max() > 1e-4


def test_output_shape_densenet() -> None:
    torch.manual_seed(0)
    net = GraspQNetwork(NetworkConfig(
        action="rotation", backbone="densenet121", num_rotations=2)).eval()
    with torch.no_grad():
        q = net(torch.randn(1, 3, 64, 64), torch.randn(1, 3, 64, 64))
    assert q.shape == (1, 2, 64, 64)
    assert torch.isfinite(q).all()


def test_rotation_zero_is_identity() -> None:
    x = _smooth_image(64)
    torch.testing.assert_close(rotate_images(x, torch.zeros(1)), x, rtol=0, atol=1e-5)


@pytest.mark.parametrize("k", [1, 3, 5, 8, 11])
def test_rotation_round_trip(k: int) -> None:
    size = 96
    x = _smooth_image(size)
    theta = torch.tensor([rotation_angle(k, 16)], dtype=torch.float64)
    back = rotate_images(rotate_images(x, theta), -theta)
    yy, xx = np.mgrid[0:size, 0:size]
    centre = (size - 1) / 2
    inner = torch.from_numpy((yy - centre) ** 2 + (xx - centre) ** 2 < (0.45 * size) ** 2)
    err = (back - x).abs()[..., inner]
    assert err.max() < 0.02  # two bilinear resamplings of a smooth map


def test_rotation_direction_matches_jaw_axis() -> None:
    """A bar along jaw_axis(k) in the heightmap is horizontal in the k-th rotated image."""
    size, num_rotations = 65, 8
    c = (size - 1) / 2
    for k in range(num_rotations):
        dc, dr = jaw_axis(k, num_rotations)
        img = torch.zeros(1, 1, size, size)
        for t in np.linspace(-20, 20, 400):
            img[0, 0, int(round(c + t * dr)), int(round(c + t * dc))] = 1.0
        theta = torch.tensor([rotation_angle(k, num_rotations)], dtype=torch.float64)
        rotated = rotate_images(img, theta)[0, 0]
        row_mass = rotated.sum(1)
        centre_rows = row_mass[int(c) - 2:int(c) + 3].sum()
        assert centre_rows > 0.9 * rotated.sum(), k


def test_input_rotation_is_equivariant_for_quarter_turns() -> None:
    """Q_k(I) equals Q_0 of I turned by theta_k, turned back (exact for 90 degree steps)."""
    net = _light(4)
    rng = np.random.default_rng(0)
    color = torch.from_numpy(rng.normal(size=(1, 3, 32, 32)).astype(np.float32))
    depth = torch.from_numpy(rng.normal(size=(1, 3, 32, 32)).astype(np.float32))
    with torch.no_grad():
        q = net(color, depth)[0]
        for k in range(4):
            turned = net(torch.rot90(color, k, (2, 3)), torch.rot90(depth, k, (2, 3)),
                         rotations=[0])[0, 0]
            torch.testing.assert_close(q[k], torch.rot90(turned, -k, (0, 1)),
                                       rtol=1e-4, atol=1e-4)


def test_input_checks() -> None:
    net = _light(4)
    with pytest.raises(ConfigError):
        net(torch.randn(1, 3, 32, 32), torch.randn(1, 3, 32, 30))
    with pytest.raises(ConfigError):
        net(torch.randn(1, 1, 32, 32), torch.randn(1, 1, 32, 32))
    with pytest.raises(ConfigError):
        net(torch.randn(1, 3, 32, 32), torch.randn(1, 3, 32, 32), rotations=[4])
    with pytest.raises(ConfigError):
        GraspQNetwork(NetworkConfig(backbone="light"), rotate="sideways")


def test_model_info_densenet() -> None:
    info = model_info(NetworkConfig(
        action="rotation", backbone="densenet121", num_rotations=16))
    json.dumps(info)
    p = info["parameters"]
    assert p["color_trunk"] == p["depth_trunk"] == 6_953_856
    assert p["total"] == p["color_trunk"] + p["depth_trunk"] + p["head"]
    # BN(2048) + conv 2048->64 + BN(64) + conv 64->32 + BN(32) + conv 32->1 (+ bias)
    assert p["head"] == 2 * 2048 + 2048 * 64 + 2 * 64 + 64 * 32 + 2 * 32 + 32 + 1
    assert info["padded_size"] == 320
    assert info["feature_shape"] == [16, 2048, 10, 10]
    assert info["output_shape"] == [1, 16, 224, 224]
    text = format_model_info(info)
    assert "6,953,856" in text and "320 x 320" in text


def test_model_info_light_features_mode() -> None:
    info = model_info(NetworkConfig(
        action="rotation", backbone="light", num_rotations=8), rotate="features", size=64)
    assert info["trunk_batch"] == 1
    assert info["padded_size"] == 96
    assert info["feature_shape"] == [1, 256, 12, 12]
    assert info["parameters"]["head"] == 2 * 256 + (256 + 4) * 64 + 2 * 64 + 64 * 32 + 2 * 32 + 33
