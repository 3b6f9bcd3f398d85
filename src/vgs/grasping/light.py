"""A light convolutional trunk for fast CPU runs (same interface as the DenseNet-121 trunk).

Layout (every convolution is 3x3 with padding 1 and no bias, followed by BatchNorm and ReLU):

=========  =================  ========  ===========
stage      convolution        stride    output
=========  =================  ========  ===========
stage 1    3 -> 32            2         32 x S/2
           32 -> 32           1         32 x S/2
stage 2    32 -> 64           2         64 x S/4
           64 -> 64           1         64 x S/4
stage 3    64 -> 128          2         128 x S/8
           128 -> 128         1         128 x S/8
=========  =================  ========  ===========

Output stride 8, 128 channels, 287,456 parameters (convolutions 286,560 plus BatchNorm
scales and shifts 896). The receptive field of an output cell is 43 x 43 input pixels:
r_l = r_{l-1} + (k - 1) * j_{l-1} with jump j_l = j_{l-1} * s_l gives 3, 7, 11, 19, 27, 43.
"""

from __future__ import annotations

from collections import OrderedDict

from torch import nn

WIDTHS = (32, 64, 128)


class LightTrunk(nn.Sequential):
    """Six 3x3 conv-BN-ReLU layers in three stride-2 stages (stride 8, 128 channels).

    Attributes:
        out_channels: Channels of the output feature map (128).
        stride: Ratio of input to output resolution (8).
    """

    out_channels: int
    stride: int

    def __init__(self) -> None:
        layers: OrderedDict[str, nn.Module] = OrderedDict()
        channels = 3
        for i, width in enumerate(WIDTHS, start=1):
            for j, stride in enumerate((2, 1), start=1):
                layers[f"conv{i}_{j}"] = nn.Conv2d(
                    channels, width, kernel_size=3, stride=stride, padding=1, bias=False
                )
                layers[f"norm{i}_{j}"] = nn.BatchNorm2d(width)
                layers[f"relu{i}_{j}"] = nn.ReLU(inplace=True)
                channels = width
        super().__init__(layers)
        self.out_channels = channels
        self.stride = 2 ** len(WIDTHS)
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, nonlinearity="relu")
            elif isinstance(m, nn.BatchNorm2d):
                nn.init.constant_(m.weight, 1.0)
                nn.init.constant_(m.bias, 0.0)


__all__ = ["LightTrunk"]
