"""Heightmap normalisation and the object mask."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from vgs.config import NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.preprocess import (
    IMAGENET_MEAN,
    IMAGENET_STD,
    color_fill_value,
    depth_fill_value,
    peg_mask,
    preprocess,
)


def test_color_normalisation_values() -> None:
    color = np.zeros((4, 5, 3), np.uint8)
    color[1, 2] = (255, 128, 0)
    c, _ = preprocess(color, np.zeros((4, 5), np.float32), NetworkConfig())
    assert c.shape == (1, 3, 4, 5) and c.dtype == torch.float32
    expected = [(v / 255.0 - m) / s for v, m, s in zip((255, 128, 0), IMAGENET_MEAN, IMAGENET_STD,
                                                        strict=True)]
    torch.testing.assert_close(c[0, :, 1, 2], torch.tensor(expected))
    torch.testing.assert_close(c[0, :, 0, 0], torch.tensor(color_fill_value()))


def test_depth_normalisation_ddd() -> None:
    cfg = NetworkConfig(depth_mean=0.01, depth_std=0.03)
    depth = np.array([[0.0, 0.04], [0.01, 0.1]], np.float32)
    _, d = preprocess(np.zeros((2, 2, 3), np.uint8), depth, cfg)
    assert d.shape == (1, 3, 2, 2)
    expected = torch.tensor([[-1 / 3, 1.0], [0.0, 3.0]])
    for ch in range(3):
        torch.testing.assert_close(d[0, ch], expected)
    assert depth_fill_value(cfg) == pytest.approx(-1 / 3)


def test_input_errors() -> None:
    cfg = NetworkConfig()
    ok_c, ok_d = np.zeros((4, 4, 3), np.uint8), np.zeros((4, 4), np.float32)
    with pytest.raises(ConfigError, match="heightmap.color"):
        preprocess(ok_c.astype(np.float32), ok_d, cfg)
    with pytest.raises(ConfigError, match="heightmap.depth"):
        preprocess(ok_c, np.zeros((4, 3), np.float32), cfg)
    with pytest.raises(ConfigError, match="heightmap.depth"):
        preprocess(ok_c, np.full((4, 4), np.nan, np.float32), cfg)


def test_peg_mask() -> None:
    depth = np.array([[0.0, 0.005], [0.0051, 0.03]], np.float32)
    np.testing.assert_array_equal(peg_mask(depth), [[False, False], [True, True]])
    np.testing.assert_array_equal(peg_mask(depth, 0.01), [[False, False], [False, True]])
    assert peg_mask(depth).dtype == bool
    with pytest.raises(ConfigError):
        peg_mask(depth, -1.0)
