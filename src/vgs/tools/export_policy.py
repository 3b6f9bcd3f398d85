"""Export a trained grasp network as plain weights and a JSON description.

``vgs export-policy RUN --out policy.pt`` writes

* ``policy.pt``: the evaluation network Q_eva of the training run as a flat
  ``{name: tensor}`` dictionary (float32, contiguous, on the CPU), which
  ``torch.load(path, weights_only=True)`` reads without any vgs class;
* ``policy.json``: what the weights are and how to run them: the heightmap (size, pixel size,
  axes), the input normalisation, the padding, the rotations, and the layers of the two trunks
  and the head in order as ``[kind, name, *arguments]`` lists:

  ====================================  ==================================================
  ``["conv", name, stride, padding]``   ``F.conv2d(x, W[name.weight], W.get(name.bias), ...)``
  ``["bn", name, eps]``                 ``F.batch_norm`` with ``name.running_mean`` / ``_var``,
                                        ``.weight``, ``.bias`` (inference)
  ``["relu", name]``                    ``F.relu``
  ``["maxpool", name, k, s, p]``        ``F.max_pool2d(x, k, s, p)``
  ``["avgpool", name, k, s]``           ``F.avg_pool2d(x, k, s)``
  ``["dense", name, layers]``           ``x = cat(x, run(x, layers))`` (a DenseNet layer)
  ``["angle", name, 4]``                ``x = cat(x, e_k)``, the angle code as constant
                                        channels (``rotate = "features"`` only)
  ====================================  ==================================================

``vgs export-policy RUN --out FOLDER`` (a path without a file suffix) writes a **policy folder**:
``FOLDER/policy.pt``, ``FOLDER/policy.json`` and a copy of the run's ``run.json``, which
``vgs evaluate --policy FOLDER`` and ``vgs heatmap FOLDER`` load without the checkpoint (the
final networks a published run commits, :mod:`vgs.rollout.policies`).

docs/grasping.md ("Using a trained network without vgs") gives the plain-torch snippet that
turns a heightmap into the Q maps with them; ``tests/test_export_policy.py`` checks that it
reproduces vgs's own Q values.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch
from torch import nn

from vgs.errors import ConfigError
from vgs.grasping.densenet import DenseBlock
from vgs.grasping.network import GraspQNetwork, padded_size
from vgs.grasping.preprocess import IMAGENET_MEAN, IMAGENET_STD
from vgs.jsonsafe import dumps
from vgs.rollout.policies import POLICY_FORMAT, POLICY_WEIGHTS, load_trained_agent

FORMAT = POLICY_FORMAT
WEIGHT_SUFFIXES = (".pt", ".pth")


@dataclass(frozen=True)
class PolicyExport:
    """What was written.

    Attributes:
        weights: The weights file.
        description: The JSON description.
        parameters: Scalar parameters and buffers written.
        run_json: The copy of the run's ``run.json`` (policy folder), else ``None``.
    """

    weights: Path
    description: Path
    parameters: int
    run_json: Path | None = None


def layer_ops(module: nn.Module, prefix: str) -> list[list[Any]]:
    """The layers of ``module`` in the order they run, as ``[kind, name, *arguments]`` lists.

    Raises:
        ConfigError: ``policy`` on a layer the description has no kind for.
    """
    if isinstance(module, DenseBlock):
        return [["dense", f"{prefix}.{name}", layer_ops(layer, f"{prefix}.{name}")]
                for name, layer in module.items()]
    if isinstance(module, nn.Conv2d):
        if module.groups != 1 or module.dilation != (1, 1):
            raise ConfigError("policy", f"{prefix}: grouped or dilated convolutions are not "
                                        "described")
        return [["conv", prefix, list(module.stride), list(module.padding)]]
    if isinstance(module, nn.BatchNorm2d):
        return [["bn", prefix, module.eps]]
    if isinstance(module, nn.ReLU):
        return [["relu", prefix]]
    if isinstance(module, nn.MaxPool2d):
        return [["maxpool", prefix, module.kernel_size, module.stride, module.padding]]
    if isinstance(module, nn.AvgPool2d):
        return [["avgpool", prefix, module.kernel_size, module.stride]]
    children = list(module.named_children())
    if not children:
        raise ConfigError("policy", f"{prefix}: no description for {type(module).__name__}")
    ops: list[list[Any]] = []
    for name, child in children:
        ops += layer_ops(child, f"{prefix}.{name}")
    return ops


TURN = ("images turn by theta about their centre with affine_grid [[cos, -sin, 0], "
        "[sin, cos, 0]] and bilinear grid_sample (align_corners=False, zeros outside); Q maps "
        "turn back by -theta")


def _rotation_text(net: GraspQNetwork) -> str:
    """How the input turns, in words, for each action and rotate mode."""
    if net.action == "position":
        perceived = ("theta = atan2(a_row, a_col) + pi/2, a the principal axis (largest "
                     "eigenvector of the covariance) of the (col, row) coordinates of the "
                     "pixels higher than 5 mm: the jaws close across the peg; ")
        return perceived + (TURN if net.rotate == "input" else "nothing turns")
    if net.rotate == "input":
        return "theta_k = 2 pi k / R; " + TURN.replace("theta", "theta_k")
    return ("theta_k = 2 pi k / R; nothing turns: the trunks see the unrotated input once, and "
            "the head's 'angle' op appends (cos theta_k, sin theta_k, cos 2 theta_k, "
            "sin 2 theta_k) as constant channels")


def describe(net: GraspQNetwork, size: int, pixel_size: float,
             extra: dict[str, Any], origin: tuple[float, float] | None = None) -> dict[str, Any]:
    """The JSON description of ``net`` for H = W = ``size`` heightmaps whose pixel (0, 0) has
    its outer corner at world ``origin`` (x0, y0) [m]."""
    cfg = net.cfg
    head = layer_ops(net.head, "head")
    if net.rotate == "features":  # the angle code joins the features after the first BN-ReLU
        head.insert(2, ["angle", "head", net.head.angle_channels])
    return {
        "format": FORMAT,
        **extra,
        "action": cfg.action,
        "backbone": cfg.backbone,
        "num_rotations": net.num_rotations,
        "rotate": net.rotate,
        "heightmap": {"size": size, "pixel_size_m": pixel_size,
                      "rows": "world +y", "columns": "world +x",
                      **({} if origin is None else {"origin_m": [*map(float, origin)]}),
                      "pixel_to_world": "x = origin_m[0] + (j + 0.5) * pixel_size_m, "
                                        "y = origin_m[1] + (i + 0.5) * pixel_size_m",
                      "color": "uint8 RGB (H, W, 3)",
                      "depth": "height above the table [m], float (H, W)"},
        "input": "x = [color / 255, depth] (4, H, W), zero-padded to padded_size; rotated; "
                 "then (x - input_mean) / input_std; depth copied into 3 channels",
        "input_mean": [*IMAGENET_MEAN, cfg.depth_mean],
        "input_std": [*IMAGENET_STD, cfg.depth_std],
        "padded_size": padded_size(size, size),
        "rotation": _rotation_text(net),
        "output": "Q (1, H, W): Q[0, i, j] is the value of closing the jaws at pixel (i, j) "
                  "across the peg's perceived axis, along (cos theta, sin theta)"
        if net.action == "position" else
        "Q (R, H, W): Q[k, i, j] is the value of closing the jaws at pixel (i, j) "
        "along (d_col, d_row) = (cos theta_k, sin theta_k)",
        "color_trunk": layer_ops(net.color_trunk, "color_trunk"),
        "depth_trunk": layer_ops(net.depth_trunk, "depth_trunk"),
        "head": head,
        "upsample": "bilinear to padded_size (align_corners=False), then crop the H x W window "
                    "at ((P - H) // 2, (P - W) // 2)",
    }


def export_policy(run_dir: Path, out: Path) -> PolicyExport:
    """Write the evaluation network of a ``vgs train`` run as plain weights plus JSON.

    Args:
        run_dir: Training run folder (``run.json``, ``checkpoint.pt``).
        out: Weights file (``.pt`` or ``.pth``); the description goes beside it as ``.json``.
            A folder (an existing one, or a path without a suffix) becomes a policy folder:
            ``policy.pt``, ``policy.json`` and a copy of ``run.json``.

    Returns:
        The written files.

    Raises:
        ConfigError: ``out`` on another suffix or a folder holding files but not this run's
            ``run.json``,
            ``policy`` if the folder holds no run.
    """
    from vgs.runfolder.common import read_json

    folder = out if out.is_dir() or not out.suffix else None
    if folder is None and out.suffix.lower() not in WEIGHT_SUFFIXES:
        raise ConfigError("out", f"{out.name}: the weights file must end in .pt or .pth, or "
                                 "name a folder")
    cfg, meta, agent, episodes = load_trained_agent(run_dir, "cpu", field="policy")
    if folder is not None:
        out = folder / POLICY_WEIGHTS
        theirs = folder / "run.json"
        if theirs.exists():
            if theirs.resolve() != (run_dir / "run.json").resolve() and read_json(theirs) != meta:
                raise ConfigError("out", f"{folder} holds another run's run.json; use a new "
                                         "folder")
        elif folder.is_dir() and any(folder.iterdir()):
            raise ConfigError("out", f"{folder} holds files and no run.json of this run; use a "
                                     "new folder")
    net: GraspQNetwork = agent.eva_net
    weights = {name: t.detach().to("cpu", torch.float32).contiguous()
               for name, t in net.state_dict().items() if not name.endswith("num_batches_tracked")}
    camera = cfg.cell.camera
    origin = (camera.center_xy[0] - camera.extent / 2, camera.center_xy[1] - camera.extent / 2)
    description = describe(net, camera.size, camera.pixel_size, {
        "weights": out.name, "source_run": str(run_dir), "mode": meta.get("mode"),
        "trained_episodes": episodes, "torch": torch.__version__,
        "tensors": len(weights), "values": int(sum(t.numel() for t in weights.values())),
    }, origin)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.save(weights, out)
    json_path = out.with_suffix(".json")
    json_path.write_text(dumps(description, indent=1))
    run_json = None
    if folder is not None:
        run_json = folder / "run.json"
        if run_json.resolve() != (run_dir / "run.json").resolve():
            run_json.write_bytes((run_dir / "run.json").read_bytes())
    return PolicyExport(out, json_path, description["values"], run_json)
