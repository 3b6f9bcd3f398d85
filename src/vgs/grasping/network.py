"""Fully convolutional grasp Q network (paper 3.1; rotations as andyzeng/visual-pushing-grasping).

Layout for an H x W heightmap, R rotations, trunk output C channels at stride s:

1. **Padding.** Colour and depth are padded to a P x P square that contains the heightmap under
   any rotation, ``P = 32 * ceil(ceil(sqrt(H^2 + W^2)) / 32)`` (320 for 224 x 224), the heightmap
   centred at offset ``((P - H) // 2, (P - W) // 2)``. The pad is zero in raw units (black
   colour, height 0 on the table), i.e. ``-mean / std`` after normalisation, as VPG pads the
   raw heightmap before normalising.
2. **Rotation** (``rotate="input"``, default, VPG-faithful). Each padded map is rotated into the
   R orientations ``theta_k = 2 * pi * k / R`` (k = 0..R-1, 360 degrees in all), all R copies
   stacked into one batch of B * R images. The rotation uses ``affine_grid``/``grid_sample``
   (bilinear, ``align_corners=False``) with the sampling matrix

       A(theta) = [[cos theta, -sin theta, 0], [sin theta, cos theta, 0]],

   so output pixel p (normalised coordinates x = column, y = row, y pointing down) reads the
   input at A(theta) p: the image turns counter-clockwise on screen by theta about its centre.
3. **Trunks.** Two parallel trunks of the chosen backbone, one on the colour (RGB) images and
   one on the depth (DDD) images, each giving (B * R, C, P/s, P/s); the two are concatenated
   channel-wise into 2C channels.
4. **Head.** Three 1x1 convolutions interleaved with BatchNorm and ReLU::

       BN(2C) - ReLU - conv1x1(2C -> 64, no bias)
       - BN(64) - ReLU - conv1x1(64 -> 32, no bias)
       - BN(32) - ReLU - conv1x1(32 -> 1, with bias)

   The last convolution keeps its bias so the Q map can carry an offset; the first two are
   followed by BatchNorm, which makes a bias redundant.
5. **Upsampling and back-rotation.** The (B * R, 1, P/s, P/s) map is bilinearly upsampled
   (``align_corners=False``) to P x P, rotated back by -theta_k (sampling matrix A(-theta_k))
   and cropped to the original H x W window, giving Q of shape (B, R, H, W).

Q[b, k, i, j] predicts the return of closing the gripper at pixel (row i, column j) with the
jaws closing, in the rotated image, along its column (x) axis; in heightmap pixel coordinates
that is the direction (d_col, d_row) = (cos theta_k, sin theta_k) (:func:`jaw_axis`).

**Position action** (``network.action = "position"``, the paper's). The network outputs one
Q map per heightmap, (B, 1, H, W). With ``rotate="input"`` each padded heightmap is turned once,
by the perceived closing angle theta of its own peg
(:func:`vgs.grasping.actions.perceived_jaw_angle`, given to :meth:`GraspQNetwork.forward` as
``angles``), so that the jaws close along the turned image's column axis as in step 2, and the
Q map is turned back by -theta; with ``rotate="none"`` the trunks see the heightmap as captured.

``rotate="features"`` (rotation action only; optional, faster, not in the paper or VPG) runs each
trunk once on the unrotated padded heightmap and handles the orientation after the trunks. Rotating
the feature map by theta_k, applying the pointwise (1x1) head and rotating back would be the
identity up to interpolation, giving R identical maps; instead the head's first convolution also
receives the angle code e_k = (cos theta_k, sin theta_k, cos 2 theta_k, sin 2 theta_k) as four
constant channels appended after its first BN-ReLU (its weight is then 64 x (2C + 4)). This trades
the trunks' rotated views for an R-fold cheaper trunk pass. """

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from vgs.config import NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.actions import jaw_axis, rotation_angle
from vgs.grasping.densenet import DenseNet121Trunk, load_trunk_weights
from vgs.grasping.light import LightTrunk
from vgs.grasping.preprocess import color_fill_value, depth_fill_value

ROTATE_MODES = ("input", "features", "none")
PAD_MULTIPLE = 32
HEAD_WIDTHS = (64, 32)
ANGLE_CHANNELS = 4
ALIGN_CORNERS = False


def padded_size(height: int, width: int) -> int:
    """Side P of the square that holds an H x W map under any rotation, a multiple of 32.

    P = 32 * ceil(ceil(sqrt(H^2 + W^2)) / 32); for H = W this is ceil(H * sqrt(2)) rounded up
    to a multiple of 32 (224 -> 317 -> 320).
    """
    diagonal = math.ceil(math.hypot(height, width))
    return PAD_MULTIPLE * math.ceil(diagonal / PAD_MULTIPLE)


def rotate_images(x: Tensor, angles: Tensor) -> Tensor:
    """Rotate square images counter-clockwise (on screen) about their centres.

    Output pixel p reads the input at A(theta) p with A(theta) = [[cos, -sin, 0], [sin, cos, 0]]
    in ``affine_grid``'s normalised coordinates (bilinear, ``align_corners=False``, zeros
    outside). For a square image normalised coordinates are isotropic, so this is a rigid
    rotation; rotating by theta and then by -theta returns the image up to interpolation.

    Args:
        x: Images (N, C, S, S).
        angles: Rotation angles (N,) [rad].

    Returns:
        Rotated images (N, C, S, S).
    """
    if x.shape[-1] != x.shape[-2]:
        raise ConfigError("network.input", f"rotation needs square images, got {tuple(x.shape)}")
    cos, sin = torch.cos(angles), torch.sin(angles)
    zero = torch.zeros_like(angles)
    theta = torch.stack(
        (torch.stack((cos, -sin, zero), -1), torch.stack((sin, cos, zero), -1)), -2
    ).to(dtype=x.dtype, device=x.device)
    grid = F.affine_grid(theta, list(x.shape), align_corners=ALIGN_CORNERS)
    return F.grid_sample(x, grid, mode="bilinear", padding_mode="zeros",
                         align_corners=ALIGN_CORNERS)


def build_trunk(backbone: str, memory_efficient: bool = False) -> nn.Module:
    """A fresh trunk: ``densenet121`` (:class:`DenseNet121Trunk`) or ``light``.

    Raises:
        ConfigError: ``network.backbone`` on an unknown name.
    """
    if backbone == "densenet121":
        return DenseNet121Trunk(memory_efficient=memory_efficient)
    if backbone == "light":
        return LightTrunk()
    raise ConfigError("network.backbone", f"unknown backbone {backbone!r}")


class GraspHead(nn.Module):
    """BN-ReLU-conv1x1(c -> 64)-BN-ReLU-conv1x1(64 -> 32)-BN-ReLU-conv1x1(32 -> 1).

    Args:
        in_channels: Channels of the concatenated trunk features (2C).
        angle_channels: Extra constant channels (the angle code) concatenated after the first
            BN-ReLU; 0 for input rotation.
    """

    def __init__(self, in_channels: int, angle_channels: int = 0) -> None:
        super().__init__()
        w1, w2 = HEAD_WIDTHS
        self.angle_channels = angle_channels
        self.norm0 = nn.BatchNorm2d(in_channels)
        self.relu0 = nn.ReLU(inplace=True)
        self.conv0 = nn.Conv2d(in_channels + angle_channels, w1, kernel_size=1, bias=False)
        self.norm1 = nn.BatchNorm2d(w1)
        self.relu1 = nn.ReLU(inplace=True)
        self.conv1 = nn.Conv2d(w1, w2, kernel_size=1, bias=False)
        self.norm2 = nn.BatchNorm2d(w2)
        self.relu2 = nn.ReLU(inplace=True)
        self.conv2 = nn.Conv2d(w2, 1, kernel_size=1, bias=True)
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight)
                if m.bias is not None:
                    nn.init.zeros_(m.bias)
            elif isinstance(m, nn.BatchNorm2d):
                nn.init.ones_(m.weight)
                nn.init.zeros_(m.bias)

    def forward(self, features: Tensor, angle_code: Tensor | None = None) -> Tensor:
        """Map features (N, c, h, w) (and an angle code (N, a)) to Q logits (N, 1, h, w)."""
        x = self.relu0(self.norm0(features))
        if self.angle_channels:
            if angle_code is None or angle_code.shape != (x.shape[0], self.angle_channels):
                raise ConfigError("network.rotate", "the features mode needs an angle code")
            code = angle_code.to(x.dtype)[:, :, None, None].expand(-1, -1, *x.shape[-2:])
            x = torch.cat((x, code), 1)
        x = self.conv0(x)
        x = self.conv1(self.relu1(self.norm1(x)))
        return self.conv2(self.relu2(self.norm2(x)))


class GraspQNetwork(nn.Module):
    """Pixel-wise grasp Q values for R orientations (see the module docstring for the layout).

    Args:
        cfg: Backbone, number of rotations R, optional trunk weights, depth normalisation.
        rotate: ``"input"`` (rotate the heightmap, VPG) or ``"features"`` (trunks run
            once; the head is conditioned on the angle); default: ``cfg.rotate``.
        memory_efficient: Gradient checkpointing inside DenseNet-121's dense layers.
        channels_last: Store convolution weights and trunk inputs in channels-last memory
            format (faster on CPU with oneDNN; results unchanged up to rounding).

    Raises:
        ConfigError: On an unknown ``rotate`` mode or a bad weights file.
    """

    def __init__(
        self,
        cfg: NetworkConfig,
        rotate: str | None = None,
        memory_efficient: bool = False,
        channels_last: bool = False,
    ) -> None:
        super().__init__()
        rotate = cfg.rotate if rotate is None else rotate
        if rotate not in ROTATE_MODES:
            raise ConfigError("network.rotate", f"must be one of {ROTATE_MODES}, got {rotate!r}")
        self.cfg = cfg
        self.action = cfg.action
        self.rotate = rotate
        self.num_rotations = cfg.q_maps
        self.color_trunk = build_trunk(cfg.backbone, memory_efficient)
        self.depth_trunk = build_trunk(cfg.backbone, memory_efficient)
        if cfg.weights is not None:
            load_trunk_weights(self.color_trunk, cfg.weights)
            load_trunk_weights(self.depth_trunk, cfg.weights)
        self.trunk_channels: int = self.color_trunk.out_channels
        self.stride: int = self.color_trunk.stride
        angle_channels = ANGLE_CHANNELS if rotate == "features" else 0
        self.head = GraspHead(2 * self.trunk_channels, angle_channels)
        self.register_buffer(
            "color_fill", torch.tensor(color_fill_value()).view(1, 3, 1, 1), persistent=False
        )
        self.register_buffer(
            "depth_fill", torch.full((1, 3, 1, 1), depth_fill_value(cfg)), persistent=False
        )
        self.channels_last = channels_last
        if channels_last:
            self.to(memory_format=torch.channels_last)

    def rotation_angle(self, k: int) -> float:
        """theta_k = 2 * pi * k / R [rad]."""
        return rotation_angle(k, self.num_rotations)

    def _check_inputs(self, color: Tensor, depth: Tensor) -> None:
        if color.ndim != 4 or color.shape[1] != 3:
            raise ConfigError("network.input", f"colour must be (B, 3, H, W), got {color.shape}")
        if depth.shape != color.shape:
            raise ConfigError(
                "network.input", f"depth {tuple(depth.shape)} != colour {tuple(color.shape)}"
            )

    def _rotation_list(self, rotations: Sequence[int] | None) -> list[int]:
        if rotations is None:
            return list(range(self.num_rotations))
        ks = [int(k) for k in rotations]
        if not ks:
            raise ConfigError("network.rotation", "needs at least one rotation index")
        for k in ks:
            rotation_angle(k, self.num_rotations)
        return ks

    def _pad(self, x: Tensor, fill: Tensor, size: int) -> Tensor:
        """Centre x in a size x size square; returns x - fill (the fill maps to 0)."""
        h, w = x.shape[-2:]
        top, left = (size - h) // 2, (size - w) // 2
        return F.pad(x - fill, (left, size - w - left, top, size - h - top))

    def _trunks(self, color: Tensor, depth: Tensor) -> Tensor:
        if self.channels_last:
            color = color.contiguous(memory_format=torch.channels_last)
            depth = depth.contiguous(memory_format=torch.channels_last)
        return torch.cat((self.color_trunk(color), self.depth_trunk(depth)), 1)

    def _angles(self, batch: int, rotations: Sequence[int] | None,
                angles: Sequence[float] | None, device: torch.device) -> tuple[Tensor, int]:
        """The turn of every trunk input, (B * n,) [rad], and n, the Q maps per heightmap."""
        if self.action == "position":
            if rotations is not None and [int(k) for k in rotations] != [0]:
                raise ConfigError("network.rotation", "the position action has one Q map (0)")
            turns = [0.0] * batch if angles is None else [float(a) for a in angles]
            if len(turns) != batch:
                raise ConfigError("network.angles", f"needs {batch} angles, got {len(turns)}")
            return torch.tensor(turns, dtype=torch.float64, device=device), 1
        ks = self._rotation_list(rotations)
        thetas = [rotation_angle(k, self.num_rotations) for k in ks]
        return torch.tensor(thetas, dtype=torch.float64, device=device).repeat(batch), len(ks)

    def forward(
        self, color: Tensor, depth: Tensor, rotations: Sequence[int] | None = None,
        angles: Sequence[float] | None = None,
    ) -> Tensor:
        """Q maps of a batch of heightmaps.

        Args:
            color: Normalised colour, (B, 3, H, W).
            depth: Normalised depth copied into three channels, (B, 3, H, W).
            rotations: Rotation action: the rotation indices to evaluate (default: all R, in
                order). Position action: ``None`` or ``[0]``.
            angles: Position action: each heightmap's perceived closing angle theta [rad]
                (default 0), by which ``rotate="input"`` turns it. Ignored otherwise.

        Returns:
            Q values (B, n, H, W): rotation action, channel j belongs to rotation
            ``rotations[j]``; position action, n = 1.

        Raises:
            ConfigError: On mismatched shapes or a rotation index outside [0, R).
        """
        self._check_inputs(color, depth)
        batch, _, height, width = color.shape
        angles_t, n_rot = self._angles(batch, rotations, angles, color.device)
        size = padded_size(height, width)
        color_fill = self.color_fill.to(color.dtype)
        depth_fill = self.depth_fill.to(depth.dtype)
        color_p = self._pad(color, color_fill, size)
        depth_p = self._pad(depth, depth_fill, size)
        angles = angles_t
        if self.rotate == "input":
            color_r = rotate_images(color_p.repeat_interleave(n_rot, 0), angles) + color_fill
            depth_r = rotate_images(depth_p.repeat_interleave(n_rot, 0), angles) + depth_fill
            q = self.head(self._trunks(color_r, depth_r))
        elif self.rotate == "none":
            q = self.head(self._trunks(color_p + color_fill, depth_p + depth_fill))
        else:
            features = self._trunks(color_p + color_fill, depth_p + depth_fill)
            code = torch.stack(
                (torch.cos(angles), torch.sin(angles), torch.cos(2 * angles),
                 torch.sin(2 * angles)), -1
            )
            q = self.head(features.repeat_interleave(n_rot, 0), code)
        q = F.interpolate(q, size=(size, size), mode="bilinear", align_corners=ALIGN_CORNERS)
        if self.rotate == "input":
            q = rotate_images(q, -angles)
        top, left = (size - height) // 2, (size - width) // 2
        q = q[:, 0, top:top + height, left:left + width]
        return q.reshape(batch, n_rot, height, width)


def count_parameters(module: nn.Module) -> int:
    """Number of scalar parameters of a module."""
    return sum(p.numel() for p in module.parameters())


def model_info(cfg: NetworkConfig, rotate: str = "input", size: int = 224) -> dict[str, Any]:
    """Parameter counts and tensor shapes of the grasp network, JSON-serialisable.

    Args:
        cfg: Network configuration.
        rotate: Rotation mode (``"input"`` or ``"features"``).
        size: Heightmap side H = W [px].

    Returns:
        A dict with ``backbone``, ``rotate``, ``num_rotations``, ``heightmap`` [H, W],
        ``padded_size`` P, ``trunk_stride``, ``trunk_channels``, ``input_shapes`` (colour and
        depth, [1, 3, H, W]), ``trunk_batch`` (images per trunk and decision),
        ``feature_shape`` ([N, 2C, P/s, P/s] after concatenation), ``output_shape``
        ([1, R, H, W]) and ``parameters`` (``color_trunk``, ``depth_trunk``, ``head``,
        ``total``).

    Raises:
        ConfigError: On a bad size or mode.
    """
    if size < 1:
        raise ConfigError("model_info.size", f"must be >= 1, got {size}")
    net = GraspQNetwork(NetworkConfig(action=cfg.action, backbone=cfg.backbone,
                                      num_rotations=cfg.num_rotations, rotate=rotate,
                                      depth_mean=cfg.depth_mean, depth_std=cfg.depth_std))
    pad = padded_size(size, size)
    feat = pad // net.stride
    trunk_batch = cfg.q_maps if rotate == "input" else 1
    params = {
        "color_trunk": count_parameters(net.color_trunk),
        "depth_trunk": count_parameters(net.depth_trunk),
        "head": count_parameters(net.head),
        "total": count_parameters(net),
    }
    return {
        "action": cfg.action,
        "backbone": cfg.backbone,
        "rotate": rotate,
        "num_rotations": cfg.q_maps,
        "heightmap": [size, size],
        "padded_size": pad,
        "trunk_stride": net.stride,
        "trunk_channels": net.trunk_channels,
        "input_shapes": {"color": [1, 3, size, size], "depth": [1, 3, size, size]},
        "trunk_batch": trunk_batch,
        "feature_shape": [trunk_batch, 2 * net.trunk_channels, feat, feat],
        "output_shape": [1, cfg.q_maps, size, size],
        "parameters": params,
    }


def format_model_info(info: dict[str, Any]) -> str:
    """Human-readable table of :func:`model_info` output."""
    p = info["parameters"]
    shape = "x".join
    rows = [
        ("backbone", f"{info['backbone']} (rotate={info['rotate']})"),
        ("action", str(info.get("action", "rotation"))),
        ("Q maps (rotations R)", str(info["num_rotations"])),
        ("heightmap", shape(str(v) for v in info["heightmap"])),
        ("padded square", f"{info['padded_size']} x {info['padded_size']}"),
        ("trunk stride / channels", f"{info['trunk_stride']} / {info['trunk_channels']}"),
        ("colour input", shape(str(v) for v in info["input_shapes"]["color"])),
        ("depth input", shape(str(v) for v in info["input_shapes"]["depth"])),
        ("images per trunk pass", str(info["trunk_batch"])),
        ("trunk features (concat.)", shape(str(v) for v in info["feature_shape"])),
        ("output Q", shape(str(v) for v in info["output_shape"])),
        ("params colour trunk", f"{p['color_trunk']:,}"),
        ("params depth trunk", f"{p['depth_trunk']:,}"),
        ("params head", f"{p['head']:,}"),
        ("params total", f"{p['total']:,}"),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k.ljust(width)}  {v}" for k, v in rows)


__all__ = [
    "GraspHead",
    "GraspQNetwork",
    "ROTATE_MODES",
    "build_trunk",
    "count_parameters",
    "format_model_info",
    "jaw_axis",
    "model_info",
    "padded_size",
    "rotate_images",
    "rotation_angle",
]
