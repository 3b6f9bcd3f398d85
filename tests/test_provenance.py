"""Every result says where it came from (issue 42, item 3): a training run and an evaluation
made by vgs running from an installed copy (not a checkout) record vgs's version, "installed
package" as the source, MuJoCo's and torch's versions, in run.json, meta.json and the parquet
schema; a resume with other recorded versions is not refused. A wheel built from a git checkout
records the commit it was built from, and ``vgs --version`` names it (issue 54, item 4)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

import vgs
from vgs.runfolder.common import provenance, read_json, source_revision

SMALL = ["--profile", "smoke", "--set", "cell.camera.size=64", "--set",
         "cell.camera.pixel_size=0.007", "--no-progress"]


def test_provenance_fields() -> None:
    p = provenance()
    assert p["vgs_version"] == metadata.version("vgs") == vgs.__version__
    assert p["mujoco_version"] == metadata.version("mujoco")
    assert p["torch_version"] == metadata.version("torch")
    assert p["source_revision"]


def test_a_checkout_records_its_commit() -> None:
    """Run from a git checkout (the tests' editable install), the source revision is the
    checkout's HEAD, with ``+modified`` when src/ differs from it."""
    root = Path(vgs.__file__).resolve().parents[2]  # src/vgs/__init__.py -> the checkout
    if not (root / ".git").exists() or shutil.which("git") is None:
        pytest.skip("vgs is not imported from a git checkout")
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True,
                          text=True, timeout=10).stdout.strip()
    assert source_revision() in (head, head + "+modified")


@pytest.mark.slow
def test_installed_copy_records_its_versions(tmp_path: Path) -> None:
    site = tmp_path / "site"
    shutil.copytree(Path(vgs.__file__).parent, site / "vgs",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(site)}

    def run(*args: str) -> None:
        proc = subprocess.run([sys.executable, "-m", "vgs.cli", *args], capture_output=True,
                              text=True, timeout=600, cwd=tmp_path, env=env)
        assert proc.returncode == 0, proc.stderr

    run("train", "--mode", "baseline", "--episodes", "1", "--out", "run", *SMALL)
    made = read_json(tmp_path / "run" / "run.json")["provenance"]
    assert made == {**provenance(), "source_revision": "installed package"}
    assert made["vgs_version"] == vgs.__version__
    # A resume by another vgs is recorded, not refused.
    meta = read_json(tmp_path / "run" / "run.json")
    meta["provenance"] = {**made, "vgs_version": "0.0.1"}
    (tmp_path / "run" / "run.json").write_text(json.dumps(meta))
    run("train", "--mode", "baseline", "--episodes", "2", "--out", "run", *SMALL)
    meta = read_json(tmp_path / "run" / "run.json")
    assert meta["provenance"]["vgs_version"] == "0.0.1" and meta["resumed_with"] == [made]

    ev = tmp_path / "res" / "eval" / "random" / "nominal"
    run("evaluate", "--policy", "random", "--episodes", "1", "--workers", "1", "--out", str(ev),
        *SMALL)
    assert read_json(ev / "meta.json")["provenance"] == made
    import pyarrow.parquet as pq

    schema = pq.read_schema(ev / "episodes.parquet").metadata
    assert {k.decode(): v.decode() for k, v in schema.items() if not k.startswith(b"pandas")} \
        == made
    run("report", "res")
    assert (f"Test episodes made with vgs {vgs.__version__} (source installed package), MuJoCo "
            f"{made['mujoco_version']}") in (tmp_path / "res" / "report.md").read_text()


@pytest.mark.slow
def test_tensorboard_logs_the_configuration(tmp_path: Path) -> None:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    proc = subprocess.run([sys.executable, "-m", "vgs.cli", "train", "--mode", "vgs",
                           "--episodes", "1", "--out", "run", *SMALL], capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    acc = EventAccumulator(str(tmp_path / "run" / "tensorboard"), size_guidance={"tensors": 0})
    acc.Reload()
    text = acc.Tensors("config/text_summary")[0].tensor_proto.string_val[0].decode()
    assert '"mode": "vgs"' in text and '"vgs_version"' in text and '"learning_rate"' in text


def _tree(root: Path) -> Path:
    """A copy of what a wheel is built from (pyproject.toml, setup.py, README.md, src/)."""
    source = Path(vgs.__file__).resolve().parents[2]
    root.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy(source / name, root / name)
    shutil.copytree(source / "src", root / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return root


def _wheel(tree: Path, dist: Path) -> Path:
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                           "--no-build-isolation", "--no-index", "-q", "-w", str(dist), str(tree)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    [wheel] = dist.glob("vgs-*.whl")
    return wheel


def test_a_wheel_records_the_commit_it_was_built_from(tmp_path: Path) -> None:
    """From a git checkout: the wheel holds vgs/build_info.json with its commit, and vgs
    installed from it (outside any checkout) prints it in --version and records it; built outside
    git, the wheel says "unknown"."""
    import zipfile

    if shutil.which("git") is None:
        pytest.skip("no git")
    tree = _tree(tmp_path / "clone")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "commit.gpgsign=false"]
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "build me"]):
        subprocess.run([*git, *args], cwd=tree, check=True, capture_output=True, timeout=60)
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=tree, capture_output=True,
                          text=True, check=True).stdout.strip()
    wheel = _wheel(tree, tmp_path / "dist")
    with zipfile.ZipFile(wheel) as archive:
        assert json.loads(archive.read("vgs/build_info.json")) == {"source_revision": head}
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "-q",
                    "--target", str(site), str(wheel)], check=True, capture_output=True,
                   timeout=300)
    env = {**os.environ, "PYTHONPATH": str(site)}
    out = tmp_path / "elsewhere"
    out.mkdir()

    def run(*args: str) -> str:
        proc = subprocess.run([sys.executable, *args], capture_output=True, text=True,
                              timeout=300, cwd=out, env=env)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout

    assert run("-c", "import vgs; print(vgs.__file__)").strip() == str(
        site / "vgs" / "__init__.py")
    assert run("-m", "vgs.cli", "--version").strip() == f"vgs {vgs.__version__} (source {head})"
    assert run("-c", "from vgs.runfolder.common import provenance; "
                     "print(provenance()['source_revision'])").strip() == head

    outside = _tree(tmp_path / "unpacked")  # an sdist unpacked: no git
    with zipfile.ZipFile(_wheel(outside, tmp_path / "dist2")) as archive:
        assert json.loads(archive.read("vgs/build_info.json")) == {"source_revision": "unknown"}
