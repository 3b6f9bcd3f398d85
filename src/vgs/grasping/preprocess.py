"""Heightmap normalisation for the grasp network, and the object mask.

The simulator delivers an orthographic RGB-D heightmap as ``color: np.uint8 (H, W, 3)`` and
``depth: np.float32 (H, W)`` (height above the table [m]). The network takes two tensors of
shape (1, 3, H, W):

* colour (RGB), scaled to [0, 1] and normalised per channel with the ImageNet statistics
  ``c' = (c / 255 - mean_c) / std_c``, mean = (0.485, 0.456, 0.406), std = (0.229, 0.224, 0.225);
* depth (DDD), ``d' = (d - depth_mean) / depth_std`` with the constants of
  :class:`vgs.config.NetworkConfig` (defaults 0.01 m and 0.03 m), copied into three channels so
  the depth trunk has the same architecture (and can load the same weights) as the colour trunk.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from vgs.config import NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.actions import check_depth, peg_mask

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)


def _check_color(color: np.ndarray) -> None:
    if not isinstance(color, np.ndarray) or color.dtype != np.uint8:
        raise ConfigError("heightmap.color", "must be a numpy uint8 array")
    if color.ndim != 3 or color.shape[2] != 3:
        raise ConfigError("heightmap.color", f"must have shape (H, W, 3), got {color.shape}")


def normalize_color(color: np.ndarray) -> Tensor:
    """ImageNet-normalised colour tensor.

    Args:
        color: RGB heightmap, uint8, shape (H, W, 3).

    Returns:
        float32 tensor (1, 3, H, W) with channel c equal to (color[..., c] / 255 - mean_c) / std_c.

    Raises:
        ConfigError: ``heightmap.color`` on a wrong dtype or shape.
    """
    _check_color(color)
    x = torch.from_numpy(np.ascontiguousarray(color)).permute(2, 0, 1).float().div_(255.0)
    mean = torch.tensor(IMAGENET_MEAN).view(3, 1, 1)
    std = torch.tensor(IMAGENET_STD).view(3, 1, 1)
    return ((x - mean) / std).unsqueeze(0).contiguous()


def normalize_depth(depth: np.ndarray, cfg: NetworkConfig) -> Tensor:
    """Normalised depth heightmap copied into three channels (DDD).

    Args:
        depth: Height above the table [m], float, shape (H, W).
        cfg: Supplies ``depth_mean`` and ``depth_std``.

    Returns:
        float32 tensor (1, 3, H, W), every channel equal to (depth - depth_mean) / depth_std.

    Raises:
        ConfigError: ``heightmap.depth`` on a wrong dtype or shape or a non-finite height.
    """
    check_depth(depth)
    d = (torch.from_numpy(np.asarray(depth, dtype=np.float32)) - cfg.depth_mean) / cfg.depth_std
    return d.view(1, 1, *d.shape).expand(1, 3, *d.shape).contiguous()


def preprocess(color: np.ndarray, depth: np.ndarray, cfg: NetworkConfig) -> tuple[Tensor, Tensor]:
    """Both network inputs of one heightmap.

    Args:
        color: RGB heightmap, uint8 (H, W, 3).
        depth: Height above the table [m], float (H, W).
        cfg: Network configuration (depth normalisation constants).

    Returns:
        ``(color, depth)`` tensors, each float32 (1, 3, H, W).

    Raises:
        ConfigError: On wrong dtypes or shapes, or if the two maps differ in size.
    """
    check_heightmaps(color, depth)
    return normalize_color(color), normalize_depth(depth, cfg)


def check_heightmaps(color: np.ndarray, depth: np.ndarray) -> None:
    """Validate a raw heightmap pair: uint8 (H, W, 3) colour, finite float (H, W) depth.

    Raises:
        ConfigError: ``heightmap.color`` or ``heightmap.depth`` on a wrong dtype or shape, a
            non-finite height, or different sizes.
    """
    _check_color(color)
    check_depth(depth)
    if color.shape[:2] != depth.shape:
        raise ConfigError(
            "heightmap.depth", f"size {depth.shape} differs from the colour map's {color.shape[:2]}"
        )


def color_fill_value() -> tuple[float, float, float]:
    """Normalised value of a black pixel, (0 - mean_c) / std_c per channel (padding value)."""
    return tuple(-m / s for m, s in zip(IMAGENET_MEAN, IMAGENET_STD, strict=True))


def depth_fill_value(cfg: NetworkConfig) -> float:
    """Normalised value of table height 0, (0 - depth_mean) / depth_std (padding value)."""
    return -cfg.depth_mean / cfg.depth_std


__all__ = [
    "IMAGENET_MEAN",
    "IMAGENET_STD",
    "check_heightmaps",
    "color_fill_value",
    "depth_fill_value",
    "normalize_color",
    "normalize_depth",
    "peg_mask",
    "preprocess",
]
