"""DenseNet-121 feature trunk in plain PyTorch (Huang et al., 2017), torchvision-compatible.

The trunk is the standard ImageNet configuration: growth rate k = 32, dense blocks of
(6, 12, 24, 16) layers, bottleneck width ``bn_size * k = 128``, 64 initial features and
compression 0.5 in the transition layers. Shapes for an input of side S (a multiple of 32):

====================  ==========================================  =================
stage                 operation                                   output
====================  ==========================================  =================
stem                  conv 7x7/2 (3->64), BN, ReLU, max-pool 3x3/2  64 x S/4
denseblock1           6 dense layers                              256 x S/4
transition1           BN, ReLU, conv 1x1 (256->128), avg-pool 2/2  128 x S/8
denseblock2           12 dense layers                             512 x S/8
transition2           BN, ReLU, conv 1x1 (512->256), avg-pool 2/2  256 x S/16
denseblock3           24 dense layers                             1024 x S/16
transition3           BN, ReLU, conv 1x1 (1024->512), avg-pool 2/2  512 x S/32
denseblock4           16 dense layers                             1024 x S/32
norm5 + ReLU          final BatchNorm and ReLU                    1024 x S/32
====================  ==========================================  =================

A dense layer maps the concatenation x = [x_0, ..., x_{l-1}] of all earlier feature maps of its
block to k new channels,

    H_l(x) = conv3x3(ReLU(BN(conv1x1(ReLU(BN(x)))))),

and the block output is the concatenation of its input and every H_l, so a block with c_0 input
channels and L layers returns c_0 + L * k channels. A transition halves the channels
(compression 0.5) and the resolution.

Parameter names equal the keys of torchvision's ``densenet121().features.state_dict()`` (for
example ``denseblock1.denselayer1.conv1.weight``), so :func:`load_trunk_weights` can read a local
torchvision weights file. The trunk holds 6,953,856 parameters.
"""

from __future__ import annotations

import re
from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path

import torch
from torch import Tensor, nn
from torch.utils.checkpoint import checkpoint

from vgs.errors import ConfigError

GROWTH_RATE = 32
BLOCK_CONFIG = (6, 12, 24, 16)
BN_SIZE = 4
NUM_INIT_FEATURES = 64
COMPRESSION = 0.5

# Old torchvision checkpoints (for example densenet121-a639ec97.pth) name the dense-layer
# modules "norm.1" instead of "norm1"; torchvision renames them with the same pattern on load.
_OLD_KEY = re.compile(
    r"^(.*denselayer\d+\.(?:norm|relu|conv))\.((?:[12])\.(?:weight|bias|running_mean|running_var))$"
)


class _DenseLayer(nn.Module):
    """One dense layer: BN-ReLU-conv1x1(c -> bn_size*k)-BN-ReLU-conv3x3(bn_size*k -> k)."""

    def __init__(
        self, in_channels: int, growth_rate: int, bn_size: int, memory_efficient: bool
    ) -> None:
        super().__init__()
        width = bn_size * growth_rate
        self.norm1 = nn.BatchNorm2d(in_channels)
        self.relu1 = nn.ReLU(inplace=True)
        self.conv1 = nn.Conv2d(in_channels, width, kernel_size=1, stride=1, bias=False)
        self.norm2 = nn.BatchNorm2d(width)
        self.relu2 = nn.ReLU(inplace=True)
        self.conv2 = nn.Conv2d(width, growth_rate, kernel_size=3, stride=1, padding=1, bias=False)
        self.memory_efficient = memory_efficient

    def _bottleneck(self, *inputs: Tensor) -> Tensor:
        return self.conv1(self.relu1(self.norm1(torch.cat(inputs, 1))))

    def forward(self, inputs: list[Tensor]) -> Tensor:
        """Return the k new channels computed from the list of earlier feature maps."""
        if self.memory_efficient and self.training and any(t.requires_grad for t in inputs):
            # Recompute the concatenation and the 1x1 bottleneck in the backward pass instead
            # of storing them: O(L) instead of O(L^2) activation memory per block.
            bottleneck = checkpoint(self._bottleneck, *inputs, use_reentrant=False)
        else:
            bottleneck = self._bottleneck(*inputs)
        return self.conv2(self.relu2(self.norm2(bottleneck)))


class DenseBlock(nn.ModuleDict):
    """L dense layers; returns the concatenation of the input and all new feature maps."""

    def __init__(
        self,
        num_layers: int,
        in_channels: int,
        growth_rate: int,
        bn_size: int,
        memory_efficient: bool,
    ) -> None:
        super().__init__()
        for i in range(num_layers):
            layer = _DenseLayer(in_channels + i * growth_rate, growth_rate, bn_size,
                                memory_efficient)
            self.add_module(f"denselayer{i + 1}", layer)

    def forward(self, x: Tensor) -> Tensor:
        features = [x]
        for layer in self.values():
            features.append(layer(features))
        return torch.cat(features, 1)


class _Transition(nn.Sequential):
    """BN-ReLU-conv1x1(c -> c_out)-avgpool2x2: compresses channels and halves the resolution."""

    def __init__(self, in_channels: int, out_channels: int) -> None:
        super().__init__()
        self.norm = nn.BatchNorm2d(in_channels)
        self.relu = nn.ReLU(inplace=True)
        self.conv = nn.Conv2d(in_channels, out_channels, kernel_size=1, stride=1, bias=False)
        self.pool = nn.AvgPool2d(kernel_size=2, stride=2)


class DenseNet121Trunk(nn.Sequential):
    """DenseNet-121 feature extractor (torchvision ``densenet121().features`` + final ReLU).

    Args:
        memory_efficient: Recompute each dense layer's concatenation and bottleneck in the
            backward pass (gradient checkpointing). Saves activation memory when training at
            the cost of roughly one extra bottleneck forward; outputs are unchanged.

    Attributes:
        out_channels: Channels of the output feature map (1024).
        stride: Ratio of input to output resolution (32).
    """

    out_channels: int
    stride: int

    def __init__(self, memory_efficient: bool = False) -> None:
        layers: OrderedDict[str, nn.Module] = OrderedDict(
            conv0=nn.Conv2d(3, NUM_INIT_FEATURES, kernel_size=7, stride=2, padding=3, bias=False),
            norm0=nn.BatchNorm2d(NUM_INIT_FEATURES),
            relu0=nn.ReLU(inplace=True),
            pool0=nn.MaxPool2d(kernel_size=3, stride=2, padding=1),
        )
        channels = NUM_INIT_FEATURES
        for i, num_layers in enumerate(BLOCK_CONFIG):
            layers[f"denseblock{i + 1}"] = DenseBlock(
                num_layers, channels, GROWTH_RATE, BN_SIZE, memory_efficient
            )
            channels += num_layers * GROWTH_RATE
            if i != len(BLOCK_CONFIG) - 1:
                out = int(channels * COMPRESSION)
                layers[f"transition{i + 1}"] = _Transition(channels, out)
                channels = out
        layers["norm5"] = nn.BatchNorm2d(channels)
        # torchvision applies this ReLU in DenseNet.forward; it has no parameters, so the
        # state-dict keys stay those of ``densenet121().features``.
        layers["relu5"] = nn.ReLU(inplace=True)
        super().__init__(layers)
        self.out_channels = channels
        self.stride = 32
        self._init_parameters()

    def _init_parameters(self) -> None:
        """torchvision's initialisation: Kaiming-normal convolutions, BN weight 1 and bias 0."""
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight)
            elif isinstance(m, nn.BatchNorm2d):
                nn.init.constant_(m.weight, 1.0)
                nn.init.constant_(m.bias, 0.0)


def _normalise_keys(state: Mapping[str, Tensor]) -> dict[str, Tensor]:
    """Strip a ``features.`` prefix (full torchvision model) and rename old-style keys."""
    keys = list(state)
    if any(k.startswith("features.") for k in keys):
        state = {k[len("features."):]: v for k, v in state.items() if k.startswith("features.")}
    out: dict[str, Tensor] = {}
    for key, value in state.items():
        match = _OLD_KEY.match(key)
        out[match.group(1) + match.group(2) if match else key] = value
    return out


def load_trunk_weights(module: nn.Module, path: str | Path) -> None:
    """Load a local weights file into a trunk, in place.

    Accepted files (``torch.save`` of a mapping from names to tensors):

    * a torchvision full-model state dict (keys ``features.*``; ``classifier.*`` is ignored),
    * a features-only state dict (keys as ``module.state_dict()``),

    either optionally wrapped as ``{"state_dict": ...}``. Old torchvision key names
    (``denselayer1.norm.1.weight``) are renamed to the current ones; missing BatchNorm
    ``num_batches_tracked`` counters are tolerated (old checkpoints lack them).

    Args:
        module: The trunk to fill (for example :class:`DenseNet121Trunk`).
        path: Path of the weights file.

    Raises:
        ConfigError: ``network.weights`` if the file is missing or unreadable, or if its keys
            or tensor shapes do not match the module.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError("network.weights", f"no weights file at {str(path)!r}")
    try:
        raw = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # any unpickling failure means a bad weights file
        raise ConfigError("network.weights", f"cannot read {str(path)!r}: {exc}") from exc
    if isinstance(raw, Mapping) and "state_dict" in raw and isinstance(raw["state_dict"], Mapping):
        raw = raw["state_dict"]
    if not isinstance(raw, Mapping) or not all(isinstance(v, Tensor) for v in raw.values()):
        raise ConfigError("network.weights", f"{str(path)!r} does not hold a state dict of tensors")
    state = _normalise_keys(raw)
    expected = module.state_dict()
    missing = sorted(
        k for k in expected if k not in state and not k.endswith("num_batches_tracked")
    )
    unexpected = sorted(k for k in state if k not in expected)
    if missing or unexpected:
        raise ConfigError(
            "network.weights",
            f"keys of {str(path)!r} do not match the trunk: {len(missing)} missing "
            f"(e.g. {missing[:3]}), {len(unexpected)} unexpected (e.g. {unexpected[:3]})",
        )
    wrong = [k for k, v in state.items() if tuple(v.shape) != tuple(expected[k].shape)]
    if wrong:
        k = wrong[0]
        raise ConfigError(
            "network.weights",
            f"{len(wrong)} tensors of {str(path)!r} have the wrong shape, e.g. {k}: "
            f"{tuple(state[k].shape)} instead of {tuple(expected[k].shape)}",
        )
    for key, value in expected.items():
        if key.endswith("num_batches_tracked") and key not in state:
            state[key] = torch.zeros_like(value)
    module.load_state_dict(state, strict=True)


__all__ = ["DenseNet121Trunk", "load_trunk_weights"]
