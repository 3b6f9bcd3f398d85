"""``vgs export-policy``: plain weights, a JSON description, and the documented plain-torch
snippet that reproduces vgs's Q maps with them."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from vgs.config import ExperimentConfig, override, profile, to_dict
from vgs.errors import ConfigError
from vgs.experiments.train import TrainState, save_checkpoint
from vgs.grasping.agent import DeltaQMonitor, GraspAgent
from vgs.grasping.replay import ReplayBuffer
from vgs.tools.export_policy import export_policy

ROOT = Path(__file__).resolve().parents[1]
VGS = str(Path(sys.executable).with_name("vgs"))


def fake_run(folder: Path, cfg: ExperimentConfig) -> GraspAgent:
    """A training run folder as ``vgs train`` leaves it, with BatchNorm statistics that are not
    the initial ones (a few forward passes in training mode)."""
    agent = GraspAgent(cfg.network, cfg.agent, seed=5)
    size = cfg.cell.camera.size
    gen = torch.Generator().manual_seed(0)
    with torch.no_grad():
        for _ in range(3):
            c, d = (torch.rand(1, 3, size, size, generator=gen) for _ in range(2))
            agent.eva_net.train()(c, d * 2 - 1, rotations=[0])
    folder.mkdir(parents=True)
    (folder / "run.json").write_text(json.dumps({"mode": "vgs", "config": to_dict(cfg)}))
    save_checkpoint(folder / "checkpoint.pt", agent, ReplayBuffer(cfg.agent.replay_capacity),
                    TrainState(7), DeltaQMonitor.from_config(cfg.agent))
    return agent


def snippet() -> str:
    text = (ROOT / "docs" / "grasping.md").read_text()
    section = text.split("## Using a trained network without vgs", 1)[1]
    return re.search(r"```python\n(.*?)```", section, flags=re.DOTALL).group(1)


def heightmap(size: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    color = rng.integers(0, 256, (size, size, 3), dtype=np.uint8)
    depth = np.zeros((size, size), np.float32)
    depth[size // 3: size // 2, size // 4: 3 * size // 4] = 0.03  # a lying peg
    return color, depth + rng.uniform(0, 0.002, depth.shape).astype(np.float32)


@pytest.mark.parametrize(("backbone", "size", "rotations", "rotate", "action"),
                         [("light", 224, 1, "input", "position"),
                          ("light", 224, 1, "none", "position"),
                          ("light", 224, 4, "input", "rotation"),
                          ("light", 224, 16, "features", "rotation"),
                          pytest.param("densenet121", 64, 2, "input", "rotation",
                                       marks=pytest.mark.slow)])
def test_documented_snippet_reproduces_q(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                         backbone: str, size: int, rotations: int,
                                         rotate: str, action: str) -> None:
    cfg = override(profile("smoke"), "network.action", action)
    cfg = override(cfg, "network.backbone", backbone)
    cfg = override(cfg, "network.num_rotations", rotations)
    cfg = override(cfg, "network.rotate", rotate)
    cfg = override(cfg, "cell.camera.size", size)
    agent = fake_run(tmp_path / "run", cfg)
    written = export_policy(tmp_path / "run", tmp_path / "policy.pt")
    assert written.description == tmp_path / "policy.json"
    weights = torch.load(written.weights, weights_only=True)
    assert all(isinstance(t, torch.Tensor) for t in weights.values())
    description = json.loads(written.description.read_text())
    assert description["num_rotations"] == rotations and description["trained_episodes"] == 7
    assert description["rotate"] == rotate
    color, depth = heightmap(size)
    expected = agent.q_values(color, depth)
    monkeypatch.chdir(tmp_path)  # the snippet opens policy.pt and policy.json
    namespace: dict[str, Any] = {}
    exec(compile(snippet(), "docs/grasping.md", "exec"), namespace)
    q = namespace["q_maps"](color, depth).numpy()
    assert q.shape == (rotations, size, size)
    np.testing.assert_allclose(q, expected, atol=1e-4 * max(1.0, np.abs(expected).max()))


def test_cli_and_bad_input(tmp_path: Path) -> None:
    fake_run(tmp_path / "run", profile("smoke"))
    proc = subprocess.run([VGS, "export-policy", "run", "--out", "out/p.pt"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "p.pt" in proc.stdout and "p.json" in proc.stdout and "weights_only=True" in proc.stdout
    json.loads((tmp_path / "out" / "p.json").read_text(), parse_constant=lambda c: 1 / 0)
    proc = subprocess.run([VGS, "export-policy", "nowhere", "--out", "p.pt"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
    assert "policy" in proc.stderr
    with pytest.raises(ConfigError, match="out"):
        export_policy(tmp_path / "run", tmp_path / "p.json")


def test_policy_json_maps_pixels_to_the_world_as_vgs_does(tmp_path: Path) -> None:
    """policy.json's heightmap origin and pixel size, through its documented formula, give the
    world point vgs's own heightmap gives for the same pixel (issue 42, item 4)."""
    from vgs.assembly.episode import EpisodeRunner

    cfg = override(override(profile("smoke"), "cell.camera.size", 64),
                   "cell.camera.pixel_size", 0.007)
    fake_run(tmp_path / "run", cfg)
    hm = json.loads(export_policy(tmp_path / "run", tmp_path / "policy.pt")
                    .description.read_text())["heightmap"]
    assert "origin_m" in hm["pixel_to_world"]
    seen = EpisodeRunner(cfg).observe(3)
    for i, j in [(0, 0), (5, 40), (63, 63), *np.argwhere(seen.depth > 0.005)[:3].tolist()]:
        x = hm["origin_m"][0] + (j + 0.5) * hm["pixel_size_m"]
        y = hm["origin_m"][1] + (i + 0.5) * hm["pixel_size_m"]
        assert (x, y) == pytest.approx(seen.pixel_to_world(i, j), abs=1e-12)
        assert seen.world_to_pixel(x, y) == (i, j)
