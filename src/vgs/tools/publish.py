"""Publishing a reproduction: the small result files and the final networks of its training runs
copied into a folder that can be committed (``vgs report DIR --publish DEST``)."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

from vgs.checkpoint import MAX_JOURNAL_BYTES, atomic_write_bytes, read_regular
from vgs.errors import ConfigError
from vgs.runfolder.common import read_json
from vgs.runfolder.layout import holds_network, train_folders

PUBLISH_POLICY_LIMIT = 10_000_000  # bytes: final networks a published run commits (light backbone)


PUBLISHED = ("reproduce.json", "report.md", "report.html", "results.csv", "figures/*.png",
             "eval/*/*/episodes.parquet", "eval/*/*/episodes.csv", "eval/*/*/summary.json",
             "train/*/episodes.csv", "train/*/run.json", "train/*/threshold.json",
             "train/*/convergence.json", "sweep/*")


def check_dest(out: Path, dest: Path) -> None:
    """Refuse a ``dest`` that holds a run folder of another kind (a training run, an
    evaluation, a sweep) or the report of another reproduction (its ``report.md`` beside a
    ``reproduce.json`` of another configuration, or none); reads only.

    Raises:
        ConfigError: ``publish``, naming what ``dest`` holds.
    """
    from vgs.errors import RunMismatchError
    from vgs.runfolder.folderkind import claim

    try:
        claim(dest, "reproduction")
    except RunMismatchError as exc:
        raise ConfigError("publish", exc.message) from None
    if (dest / "report.md").exists():
        theirs = read_json(dest / "reproduce.json") if (dest / "reproduce.json").exists() \
            else None
        mine = read_json(out / "reproduce.json") if (out / "reproduce.json").exists() else None
        if theirs is None or mine is None or theirs["config"] != mine["config"]:
            raise ConfigError("publish", f"{dest} holds the report of another reproduction "
                                         "(report.md); publish into a new folder, or remove "
                                         "it first")


def publish(out: Path, dest: Path) -> list[Path]:
    """Copy the small result files of a reproduction (no checkpoints, no TensorBoard logs, no
    journals) from ``out`` to ``dest`` (e.g. ``docs/results/quick``), keeping the layout, and
    the final networks of each finished training run as a policy folder ``dest/<mode>/``
    (``dest/<run>/`` when a mode has several runs): ``policy.pt``, ``policy.json`` and
    ``run.json``, which ``vgs evaluate --policy dest/<mode>`` loads on a fresh clone
    (:func:`vgs.tools.export_policy.export_policy`). Networks over
    ``PUBLISH_POLICY_LIMIT`` (a DenseNet-121 policy) are not published, with a warning.

    Returns:
        The copied files.

    Raises:
        ConfigError: If ``out`` holds no report, ``dest`` another kind of run folder or
            another reproduction's report (:func:`check_dest`), or a policy folder in ``dest``
            holds another run.
    """
    if not (out / "report.md").exists():
        raise ConfigError("report", f"{out} holds no report.md; run vgs report first")
    check_dest(out, dest)
    copied = []
    for pattern in PUBLISHED:
        for src in sorted(out.glob(pattern)):
            if src.is_symlink() or not src.is_file():  # a link's contents are not results
                continue
            target = dest / src.relative_to(out)
            target.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(target, read_regular(src, MAX_JOURNAL_BYTES))
            shutil.copystat(src, target)
            copied.append(target)
    finished = [run for run in train_folders(out)
                if holds_network(run) and (run / "convergence.json").exists()]
    if finished:
        from vgs.tools.export_policy import export_policy

        modes = [str(read_json(run / "run.json").get("mode")) for run in finished]
        for run, mode in zip(finished, modes, strict=True):
            folder = dest / (mode if modes.count(mode) == 1 else run.name)
            written = export_policy(run, folder)
            files = [written.weights, written.description, folder / "run.json"]
            size = written.weights.stat().st_size
            if size > PUBLISH_POLICY_LIMIT:
                # A DenseNet-121 policy (about 57 MB) is too large to commit: users train it.
                for f in files:
                    f.unlink(missing_ok=True)
                if folder.exists() and not any(folder.iterdir()):
                    folder.rmdir()
                warnings.warn(f"{run.name}: its final networks take {size / 1e6:.0f} MB, over "
                              f"the {PUBLISH_POLICY_LIMIT / 1e6:.0f} MB a published run commits; "
                              "not published", stacklevel=2)
                continue
            copied += files
    return copied
