"""Configuration files (``--config FILE``): what ``vgs config --json`` writes reads back exactly,
TOML and nested tables, a run folder's recorded configuration, ``--set`` on top, and the one-line
refusals."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from vgs.cli import build_parser, config_from_args, main
from vgs.config import PROFILES, profile, read_config_file, to_dict
from vgs.errors import ConfigError


def _plain(cfg: object) -> object:
    """A configuration as its JSON record reads (tuples as lists)."""
    return json.loads(json.dumps(to_dict(cfg)))


def _config_json(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(["config", *argv, "--json"]) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_config_json_reads_back_exactly(name: str, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    written = _config_json(capsys, "--profile", name)
    path = tmp_path / "c.json"
    path.write_text(written)
    assert _config_json(capsys, "--config", str(path)) == written
    assert to_dict(read_config_file(path)) == to_dict(profile(name))


def test_set_and_cell_flags_apply_on_top_of_the_file(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "c.json"
    path.write_text(_config_json(capsys, "--profile", "smoke"))
    args = build_parser().parse_args(["demo", "--config", str(path), "--peg-mass", "0.6",
                                      "--set", "train.episodes=7"])
    cfg = config_from_args(args)
    assert cfg.name == "smoke" and cfg.cell.peg.mass == 0.6 and cfg.train.episodes == 7
    assert cfg.network == profile("smoke").network


def test_toml_and_nested_json_tables(tmp_path: Path) -> None:
    toml = tmp_path / "c.toml"
    toml.write_text('name = "mine"\nseed = 3\n[train]\nepisodes = 12\n[cell.peg]\nmass = 0.6\n'
                    '[reproduce]\nconditions = ["nominal", "mass"]\n')
    cfg = read_config_file(toml)
    assert (cfg.name, cfg.seed, cfg.train.episodes, cfg.cell.peg.mass) == ("mine", 3, 12, 0.6)
    assert cfg.reproduce.conditions == ("nominal", "mass")  # lists become the tuples
    # every key it leaves out is the paper profile's
    assert cfg.network == profile("paper").network and cfg.agent == profile("paper").agent
    nested = tmp_path / "n.json"
    nested.write_text(json.dumps(to_dict(profile("quick"))))
    assert to_dict(read_config_file(nested)) == to_dict(profile("quick"))


def test_a_run_folders_recorded_configuration(tmp_path: Path) -> None:
    """The metadata file, or the folder itself; a field added since the run takes the value
    the run was made with (network.action), as a resume reads it."""
    cfg = profile("quick")
    recorded = to_dict(cfg)
    del recorded["network"]["action"]  # recorded before the field existed
    (tmp_path / "run.json").write_text(json.dumps({"mode": "vgs", "config": recorded}))
    args = build_parser().parse_args(["config", "--config", str(tmp_path)])
    got = config_from_args(args)
    assert got.network.action == "rotation" and got.train == cfg.train
    published = Path(__file__).parents[1] / "docs/results/paper_light_s0"
    repro = json.loads((published / "reproduce.json").read_text())
    args = build_parser().parse_args(["config", "--config", str(published)])
    got = _plain(config_from_args(args))

    def flat(d: dict, prefix: str = "") -> dict:
        out = {}
        for k, v in d.items():
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {prefix + k: v})
        return out

    # Every recorded key as recorded; the keys added since take their recorded-before values.
    recorded_keys = flat(repro["config"])
    assert {k: v for k, v in flat(got).items() if k in recorded_keys} == recorded_keys
    assert got["assembly"]["longer_end_margin"] == 1.0  # the old rule: F/T picks the end


@pytest.mark.parametrize(
    ("text", "suffix", "field", "words"),
    [
        ('[{"key": "cell.peg.mas", "value": 1}]', ".json", "cell.peg.mas", "no such"),
        ('[{"key": "cell.peg", "value": 1}]', ".json", "cell.peg", "group of keys"),
        ('{"cell": {"peg": {"mass": -1}}}', ".json", "peg.mass", "positive"),
        ('[1, 2]', ".json", "config", "key, value"),
        ('"text"', ".json", "config", "no configuration"),
        ("{not json", ".json", "config", "not valid JSON"),
        ("[cell\n", ".toml", "config", "not valid TOML"),
    ],
)
def test_bad_files_name_the_key(tmp_path: Path, text: str, suffix: str, field: str,
                                words: str) -> None:
    path = tmp_path / f"c{suffix}"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        read_config_file(path)
    assert info.value.field == field and words in info.value.message


def test_config_with_profile_or_missing_file_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "c.json"
    path.write_text(_config_json(capsys, "--profile", "smoke"))
    assert main(["config", "--config", str(path), "--profile", "smoke"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--config and --profile" in err
    assert main(["demo", "--config", str(tmp_path / "none.json")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["config", "--config", str(tmp_path)]) == 2  # a folder without metadata
    assert "without a run's metadata" in capsys.readouterr().err


@pytest.mark.slow
def test_train_from_the_file_records_the_profiles_configuration(tmp_path: Path) -> None:
    """``vgs train --config c.json`` writes the same run.json configuration as ``--profile``."""
    def vgs(*args: str) -> None:
        result = subprocess.run([sys.executable, "-m", "vgs.cli", *args], capture_output=True,
                                text=True, timeout=600)
        assert result.returncode == 0, result.stderr

    small = ["--mode", "baseline", "--episodes", "1", "--no-progress",
             "--set", "cell.camera.size=64", "--set", "cell.camera.pixel_size=0.007"]
    (tmp_path / "c.json").write_text(subprocess.run(
        [sys.executable, "-m", "vgs.cli", "config", "--profile", "smoke", "--json"],
        capture_output=True, text=True, check=True).stdout)
    vgs("train", "--config", str(tmp_path / "c.json"), "--out", str(tmp_path / "a"), *small)
    vgs("train", "--profile", "smoke", "--out", str(tmp_path / "b"), *small)
    a, b = (json.loads((tmp_path / run / "run.json").read_text()) for run in ("a", "b"))
    assert a["config"] == b["config"] and a["config"]["name"] == "smoke"
    # the run's record reads back as the same configuration
    vgs("config", "--config", str(tmp_path / "a"), "--json")
    assert _plain(read_config_file(tmp_path / "a" / "run.json")) == a["config"]
