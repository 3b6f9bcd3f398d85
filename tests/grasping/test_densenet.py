"""DenseNet-121 trunk: size, shapes, torchvision key names, weight loading."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from vgs.config import NetworkConfig
from vgs.errors import ConfigError
from vgs.grasping.densenet import DenseBlock, DenseNet121Trunk, load_trunk_weights
from vgs.grasping.network import GraspQNetwork

TORCHVISION_FEATURES_PARAMS = 6_953_856  # sum of numel over densenet121().features.parameters()


@pytest.fixture(scope="module")
def trunk() -> DenseNet121Trunk:
    torch.manual_seed(0)
    return DenseNet121Trunk()


def test_parameter_count_matches_torchvision(trunk: DenseNet121Trunk) -> None:
    assert sum(p.numel() for p in trunk.parameters()) == TORCHVISION_FEATURES_PARAMS


def test_state_dict_keys_follow_torchvision(trunk: DenseNet121Trunk) -> None:
    keys = list(trunk.state_dict())
    # 1 conv0 + 5 norm0 + 58 dense layers * (2 BN * 5 + 2 conv) + 3 transitions * 6 + 5 norm5
    assert len(keys) == 725
    for key in (
        "conv0.weight",
        "norm0.running_var",
        "denseblock1.denselayer1.norm1.weight",
        "denseblock1.denselayer6.conv2.weight",
        "transition3.conv.weight",
        "denseblock3.denselayer24.norm2.num_batches_tracked",
        "denseblock4.denselayer16.conv2.weight",
        "norm5.bias",
    ):
        assert key in keys
    assert trunk.state_dict()["denseblock4.denselayer16.norm1.weight"].shape == (992,)
    assert trunk.state_dict()["transition1.conv.weight"].shape == (128, 256, 1, 1)


def test_output_shape_and_relu(trunk: DenseNet121Trunk) -> None:
    trunk.eval()
    with torch.no_grad():
        out = trunk(torch.randn(2, 3, 64, 64))
    assert trunk.out_channels == 1024 and trunk.stride == 32
    assert out.shape == (2, 1024, 2, 2)
    assert out.min() >= 0.0


def test_memory_efficient_matches_plain() -> None:
    """Checkpointed dense layers give the same outputs and gradients (one small block)."""
    torch.manual_seed(1)
    plain = DenseBlock(3, 16, growth_rate=8, bn_size=2, memory_efficient=False)
    efficient = DenseBlock(3, 16, growth_rate=8, bn_size=2, memory_efficient=True)
    efficient.load_state_dict(plain.state_dict())
    x = torch.randn(2, 16, 8, 8)
    outs, grads = [], []
    for net in (plain, efficient):
        net.train()
        xi = x.clone().requires_grad_(True)
        y = net(xi)
        (y ** 2).sum().backward()
        outs.append(y.detach())
        grads.append(xi.grad)
    assert outs[0].shape == (2, 16 + 3 * 8, 8, 8)
    torch.testing.assert_close(outs[0], outs[1])
    torch.testing.assert_close(grads[0], grads[1])
    assert DenseNet121Trunk(memory_efficient=True).denseblock1.denselayer1.memory_efficient


def _randomised(trunk: DenseNet121Trunk, seed: int) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    return {
        k: (v if v.dtype == torch.long else torch.randn(v.shape, generator=g))
        for k, v in trunk.state_dict().items()
    }


def test_load_full_torchvision_state_dict(trunk: DenseNet121Trunk, tmp_path: Path) -> None:
    state = _randomised(trunk, 3)
    full = {f"features.{k}": v for k, v in state.items()}
    full["classifier.weight"] = torch.zeros(1000, 1024)
    full["classifier.bias"] = torch.zeros(1000)
    path = tmp_path / "densenet121_full.pth"
    torch.save(full, path)
    fresh = DenseNet121Trunk()
    load_trunk_weights(fresh, path)
    for k, v in fresh.state_dict().items():
        torch.testing.assert_close(v, state[k])


def test_load_features_only_and_old_key_names(trunk: DenseNet121Trunk, tmp_path: Path) -> None:
    state = _randomised(trunk, 4)
    # Old torchvision files: "denselayer1.norm.1.weight" and no num_batches_tracked.
    old = {}
    for k, v in state.items():
        if k.endswith("num_batches_tracked"):
            continue
        old[k.replace(".norm1.", ".norm.1.").replace(".conv2.", ".conv.2.")] = v
    assert any(".norm.1." in k for k in old)
    path = tmp_path / "old.pth"
    torch.save(old, path)
    fresh = DenseNet121Trunk()
    load_trunk_weights(fresh, path)
    loaded = fresh.state_dict()
    for k, v in state.items():
        if not k.endswith("num_batches_tracked"):
            torch.testing.assert_close(loaded[k], v)


def test_load_errors(trunk: DenseNet121Trunk, tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as err:
        load_trunk_weights(trunk, tmp_path / "missing.pth")
    assert err.value.field == "network.weights"

    bad_keys = {k.replace("denseblock", "block"): v for k, v in trunk.state_dict().items()}
    torch.save(bad_keys, tmp_path / "bad_keys.pth")
    with pytest.raises(ConfigError, match="missing") as err:
        load_trunk_weights(trunk, tmp_path / "bad_keys.pth")
    assert err.value.field == "network.weights"

    wrong_shape = dict(trunk.state_dict())
    wrong_shape["conv0.weight"] = torch.zeros(64, 3, 3, 3)
    torch.save(wrong_shape, tmp_path / "wrong_shape.pth")
    with pytest.raises(ConfigError, match="shape"):
        load_trunk_weights(trunk, tmp_path / "wrong_shape.pth")

    (tmp_path / "garbage.pth").write_bytes(b"not a checkpoint")
    with pytest.raises(ConfigError, match="cannot read"):
        load_trunk_weights(trunk, tmp_path / "garbage.pth")


def test_network_loads_weights_into_both_trunks(trunk: DenseNet121Trunk, tmp_path: Path) -> None:
    state = _randomised(trunk, 5)
    path = tmp_path / "features.pth"
    torch.save(state, path)
    net = GraspQNetwork(NetworkConfig(
        action="rotation", backbone="densenet121", num_rotations=2, weights=str(path)))
    for sub in (net.color_trunk, net.depth_trunk):
        torch.testing.assert_close(sub.state_dict()["conv0.weight"], state["conv0.weight"])
