"""Training's parallel episodes on the episode pool: local processes and Ray actors give the
same episode table (issue 18, item 3)."""

from __future__ import annotations

from pathlib import Path

import pytest

from test_train_resume import rows, tiny_config
from vgs.config import override
from vgs.errors import ConfigError
from vgs.experiments import train as train_mod


def two_parallel():
    cfg = override(override(tiny_config(), "train.checkpoint_every", 2), "train.episodes", 4)
    return override(cfg, "train.parallel_episodes", 2)


@pytest.mark.slow
def test_local_and_ray_training_give_identical_tables(tmp_path: Path) -> None:
    pytest.importorskip("ray", reason="the Ray extra is part of the dev install")
    cfg = two_parallel()
    local = rows(train_mod.train(cfg, "vgs", tmp_path / "local", progress=False))
    on_ray = rows(train_mod.train(cfg, "vgs", tmp_path / "ray", progress=False,
                                  backend="ray"))
    assert [r["episode"] for r in local] == ["0", "1", "2", "3"]
    assert on_ray == local


def test_unknown_backend_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="backend"):
        train_mod.train(two_parallel(), "vgs", tmp_path / "run", progress=False,
                        backend="dask")
    assert not (tmp_path / "run").exists()


def test_vgs_train_passes_the_backend_flags(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """``vgs train --backend ray --ray-address ADDR`` as ``vgs evaluate`` takes them."""
    from vgs.cli import main

    seen: dict[str, object] = {}

    def fake_train(cfg, mode, out, **kwargs):
        seen.update(kwargs, mode=mode)
        return out

    monkeypatch.setattr(train_mod, "train", fake_train)
    args = ["train", "--mode", "vgs", "--profile", "smoke", "--out", str(tmp_path / "run"),
            "--no-progress"]
    assert main([*args, "--backend", "ray", "--ray-address", "auto"]) == 0
    assert (seen["backend"], seen["ray_address"], seen["mode"]) == ("ray", "auto", "vgs")
    assert main(args) == 0
    assert (seen["backend"], seen["ray_address"]) == ("local", None)
