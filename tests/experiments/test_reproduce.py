"""Resuming a reproduction folder: which saved configurations count as the same."""

from __future__ import annotations

from pathlib import Path

import pytest

from vgs.config import override, profile, same_config, to_dict
from vgs.errors import ConfigError
from vgs.experiments.reproduce import Reproduction


def test_fields_added_later_take_their_defaults() -> None:
    """A folder saved before a field existed (here network.precision) stays resumable."""
    cfg = profile("quick")
    saved = to_dict(cfg)
    del saved["network"]["precision"]
    assert same_config(saved, cfg)
    assert not same_config(saved, override(cfg, "network.precision", "bfloat16"))


def test_other_configurations_are_refused(tmp_path: Path) -> None:
    cfg = profile("smoke")
    assert not same_config(to_dict(cfg), override(cfg, "train.episodes", 7))
    assert not same_config({"no_such_field": 1}, cfg)
    assert not same_config(None, cfg)
    Reproduction(cfg, tmp_path, workers=1, progress=False)  # writes reproduce.json
    Reproduction(cfg, tmp_path, workers=1, progress=False)  # the same: resumes
    with pytest.raises(ConfigError, match="another configuration"):
        Reproduction(override(cfg, "train.episodes", 7), tmp_path, workers=1, progress=False)


def test_evaluate_stage_refuses_unfinished_training(tmp_path: Path) -> None:
    """Evaluating before training ends would keep half-trained rows on resume."""
    rep = Reproduction(profile("smoke"), tmp_path, workers=1, progress=False)
    with pytest.raises(ConfigError, match="training has not finished"):
        rep.evaluate()


def test_train_stage_passes_the_backend_to_training(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``vgs reproduce --backend ray`` runs the training runs' parallel episodes on Ray too."""
    from vgs.experiments import reproduce

    calls: list[tuple[str, str, str | None]] = []

    def fake_train(cfg, mode, out, **kwargs):
        calls.append((mode, kwargs["backend"], kwargs["ray_address"]))
        return out

    monkeypatch.setattr(reproduce, "train", fake_train)
    Reproduction(profile("smoke"), tmp_path, workers=1, backend="ray", ray_address="auto",
                 progress=False).train()
    assert calls and all(c[1:] == ("ray", "auto") for c in calls)
    assert {c[0] for c in calls} == {"vgs", "baseline"}
