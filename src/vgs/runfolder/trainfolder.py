"""What a training run keeps in its folder: ``run.json`` (the request, checked on resume by
:func:`check_start`), the episode table (``episodes.csv``, checked row by row on resume) and the
checkpoint (networks, optimiser, replay, RNG states and counters; pickle-free,
:mod:`vgs.checkpoint`). :mod:`vgs.experiments.train` writes them; :func:`load_checkpoint` also
serves the policies that load a trained agent."""

from __future__ import annotations

import csv
import os
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from vgs import checkpoint
from vgs.config import ExperimentConfig, to_dict
from vgs.errors import CheckpointError, ConfigError, CorruptFileError, RunMismatchError
from vgs.grasping.agent import DeltaQMonitor, GraspAgent
from vgs.grasping.replay import ReplayBuffer, maps_digest
from vgs.runfolder.common import check_request, host, provenance, read_json, source_revision

# Column vocabulary of vgs.columns; booleans are written True/False (0/1 before 2026-12).
CSV_COLUMNS = (
    "episode", "mode", "seed", "epsilon", "explored", "rotation", "row", "col", "q_value",
    "grasp_success", "grasp_offset_mm", "grasp_offset_com_mm", "across_mm",
    "jaw_misalignment_deg",
    "assembly_success", "assembly_time_s", "adjustments", "failure_reason", "r_grasp",
    "r_assembly", "reward",
    "threshold_s", "loss", "delta_q",
    "wall_s",
)


# from EpisodeRecord.to_row()
RECORD_COLUMNS = ("grasp_success", "grasp_offset_mm", "grasp_offset_com_mm", "across_mm",
                  "jaw_misalignment_deg",
                  "assembly_success", "assembly_time_s", "adjustments", "failure_reason")


def episode_seed(root: int, episode: int) -> int:
    """Seed of one episode from (root seed, episode index)."""
    return int(np.random.SeedSequence([root, episode]).generate_state(1)[0])


@dataclass
class TrainState:
    """Everything a checkpoint restores besides the networks."""

    episode: int = 0
    threshold: float | None = None
    exploration_times: list[float] | None = None
    rng_state: dict[str, Any] | None = None
    table_sha256: str | None = None
    run: dict[str, Any] | None = None  # the run's identity (common.run_identity)


def read_rows(path: Path, cfg: ExperimentConfig, mode: str, keep: int,
              digest: str | None = None) -> list[str]:
    """The header and the rows of ``episodes.csv`` before episode ``keep`` (the checkpoint's),
    checked, as the lines of the file.

    Each kept row must be episode 0, 1, ... in order, of this mode and with the episode's
    planned seed, and the kept lines must hash to ``digest`` (SHA-256 recorded by the
    checkpoint), so a row changed after its checkpoint is caught. Rows from ``keep`` on were
    written after the checkpoint and are dropped (a line cut short by a kill is among them).

    Raises:
        CorruptFileError: Naming the file and line of an unreadable or foreign row, or when
            fewer rows than the checkpoint's episode count are left or they were changed.
    """
    header = ",".join(CSV_COLUMNS) + "\r\n"
    if not path.exists():
        if keep:
            raise CorruptFileError(path, f"is missing but the checkpoint is at episode {keep}; "
                                         "restore it or train again into a new folder")
        return [header]
    data = checkpoint.read_regular(path, checkpoint.MAX_JOURNAL_BYTES)  # no symlink, FIFO
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise CorruptFileError(path, "is not UTF-8 text", line=line) from None
    lines = text.splitlines(keepends=True)
    if not lines:
        if keep:
            raise CorruptFileError(path, f"is empty but the checkpoint is at episode {keep}")
        return [header]
    if lines[0].rstrip("\r\n") != header.rstrip("\r\n"):
        raise CorruptFileError(path, "is not vgs's training table header", line=1)
    for number, line in enumerate(lines[1:keep + 1], start=2):
        want = number - 2
        fields = next(csv.reader([line]), [])
        if len(fields) != len(CSV_COLUMNS) or not line.endswith("\n"):
            raise CorruptFileError(path, "is not a row of this table", line=number)
        record = dict(zip(CSV_COLUMNS, fields, strict=True))
        try:
            episode, seed = int(record["episode"]), int(record["seed"])
        except ValueError:
            raise CorruptFileError(path, "is not a row of this table", line=number) from None
        if episode != want or seed != episode_seed(cfg.seed, want) or record["mode"] != mode:
            raise CorruptFileError(path, f"is not episode {want} of this run (episode "
                                         f"{record['episode']}, seed {record['seed']}, mode "
                                         f"{record['mode']}); restore the file or train again "
                                         "into a new folder", line=number)
    kept = lines[:keep + 1]
    if len(kept) - 1 < keep:
        raise CorruptFileError(path, f"holds {len(kept) - 1} rows but the checkpoint is at "
                                     f"episode {keep}; restore it or train again into a new "
                                     "folder")
    if digest is not None and sha256_hex("".join(kept).encode("utf-8")) != digest:
        raise CorruptFileError(path, f"rows 0-{keep - 1} differ from those the checkpoint saw; "
                                     "restore the file or train again into a new folder")
    return kept


def sha256_hex(data: bytes) -> str:
    import hashlib

    return hashlib.sha256(data).hexdigest()


def open_table(path: Path, lines: list[str]) -> Any:
    """Append-only per-episode table, rewritten (atomically) with the checked ``lines`` first."""
    checkpoint.atomic_write_text(path, "".join(lines))
    f = checkpoint.open_append(path)
    return f, csv.DictWriter(f, fieldnames=CSV_COLUMNS)


def save_checkpoint(path: Path, agent: GraspAgent, replay: ReplayBuffer, state: TrainState,
                    monitor: DeltaQMonitor) -> None:
    """Write atomically and pickle-free (:mod:`vgs.checkpoint`): a kill never leaves half a
    checkpoint, and loading it runs no code.

    A target network equal to the evaluation network bit for bit (just synced: checkpoints
    every 50 episodes of 2 updates fall on the syncs of a 50-update period) is not stored
    again; :func:`load_checkpoint` copies the evaluation network into it. That is a third of a
    light-backbone checkpoint."""
    agent_state = agent.state_dict()
    replay_state = replay.state_dict()
    arrays = {k: None if v is None else torch.from_numpy(np.ascontiguousarray(v))
              for k, v in replay_state.pop("arrays").items()}
    tensors = {"eva_net": agent_state.pop("eva_net"), "optimizer": agent_state.pop("optimizer"),
               "replay_arrays": arrays, "torch_rng": torch.get_rng_state()}
    meta = {"episode": state.episode, "threshold": state.threshold,
            "exploration_times": state.exploration_times, "rng_state": state.rng_state,
            "monitor": monitor.state_dict(), "agent": agent_state, "replay": replay_state,
            "table_sha256": state.table_sha256, "run": state.run}
    newest = replay.newest()
    if replay.keeps_scenes and newest is not None:  # checked on resume (module docstring)
        scene = replay.scene(newest)
        meta["replay_check"] = {"scene": scene, "sha256": maps_digest(*replay.maps(scene))}
    checkpoint.save(path, tensors, meta)


def _scenes_from_maps(path: Path, arrays: dict[str, Any], replay: ReplayBuffer,
                      root_seed: int | None) -> dict[str, Any]:
    """The replay arrays of a checkpoint that kept heightmaps (``vgs-checkpoint/2``) as scene
    seeds: the training loop adds one transition per episode, so a transition's serial is its
    episode and its scene is ``episode_seed(root_seed, serial)``. The oldest, a middle and the
    newest transition are re-rendered and must equal the stored maps bit for bit.

    Raises:
        CheckpointError: If the stored maps are not those this host renders for the scenes.
    """
    common = {k: v for k, v in arrays.items()
              if k not in ("color", "depth", "next_color", "next_depth")}
    if arrays["color"] is None:
        return {"scene": None, **common}
    if root_seed is None or arrays["next_color"] is not None or arrays["has_next"].any():
        raise CheckpointError(path, "holds a replay of heightmaps that cannot be turned into "
                                    "scene seeds; train again into a new folder")
    serials = arrays["serial"].astype(np.int64)
    scenes = np.array([episode_seed(root_seed, int(e)) for e in serials], np.int64)
    order = np.argsort(serials, kind="stable")
    for slot in sorted({int(order[0]), int(order[len(order) // 2]), int(order[-1])}):
        color, depth = replay.render(int(scenes[slot]))
        if not (np.array_equal(color, arrays["color"][slot])
                and np.array_equal(np.asarray(depth, np.float32), arrays["depth"][slot])):
            raise CheckpointError(path, f"holds replay heightmaps (vgs-checkpoint/2) that differ "
                                        f"from those this host renders for their scenes "
                                        f"(episode {int(serials[slot])}); finish the run with "
                                        "the vgs that wrote it or train again into a new folder")
    return {"scene": scenes, **common}


def load_checkpoint(path: Path, agent: GraspAgent, replay: ReplayBuffer | None = None,
                    monitor: DeltaQMonitor | None = None, device: str = "cpu",
                    root_seed: int | None = None) -> TrainState:
    """Restore a :func:`save_checkpoint` file into ``agent`` (and ``replay``, ``monitor``, the
    torch RNG when given); return the counters.

    A scene-keyed ``replay`` re-renders the newest transition's maps and compares them with
    the hash the checkpoint recorded; one from a checkpoint that kept heightmaps is turned into
    scene seeds with ``root_seed`` (:func:`_scenes_from_maps`).

    Raises:
        CheckpointError: If the file is not a vgs checkpoint, is damaged, or does not fit, or
            this host renders the replay's scenes differently from the host that wrote it.
    """
    tensors, meta = checkpoint.load(path, map_location=device)
    try:
        # A checkpoint written before the target network was removed may hold one: not read.
        agent.load_state_dict({**meta["agent"], "eva_net": tensors["eva_net"],
                               "optimizer": tensors["optimizer"]})
        if replay is not None:
            arrays = {k: None if v is None else v.cpu().numpy()
                      for k, v in tensors["replay_arrays"].items()}
            if replay.keeps_scenes and "scene" not in arrays and "color" in arrays:
                arrays = _scenes_from_maps(path, arrays, replay, root_seed)
            replay.load_state_dict({**meta["replay"], "arrays": arrays})
            check = meta.get("replay_check")
            if replay.keeps_scenes and check is not None and replay.render is not None:
                if maps_digest(*replay.render(int(check["scene"]))) != check["sha256"]:
                    raise CheckpointError(path, f"re-renders its replay heightmaps differently "
                                                f"on this host (scene {check['scene']}), whose "
                                                "MuJoCo, NumPy or vgs differs from the writer's; "
                                                "resume it where it was written, or train again "
                                                "into a new folder")
        if monitor is not None:
            monitor.load_state_dict(meta["monitor"])
            torch.set_rng_state(tensors["torch_rng"].cpu())
        return TrainState(int(meta["episode"]), meta["threshold"], meta["exploration_times"],
                          meta["rng_state"], meta.get("table_sha256"), meta.get("run"))
    except ConfigError as exc:
        raise CheckpointError(path, f"does not fit this run ({exc})") from None
    except (KeyError, TypeError, ValueError, AttributeError, RuntimeError) as exc:
        raise CheckpointError(path, f"is incomplete ({type(exc).__name__}: {exc})") from None


def git_revision() -> str:
    """The source revision (:func:`vgs.runfolder.common.source_revision`): a commit, or
    ``"installed package"`` outside a checkout."""
    return source_revision()


def check_start(cfg: ExperimentConfig, mode: str, out: Path, threads: int | None = None
                ) -> tuple[int, int, dict[str, Any] | None]:
    """Check the request against ``run.json`` without writing anything.

    Args:
        threads: Torch CPU threads asked for (default: up to 4, at most the cores). A run
            keeps the count it started with (``torch_threads``): another count sums in
            another order and moves the losses in the 4th digit.

    Returns:
        The number of episodes the epsilon schedule spans, the run's torch threads, and the
        ``run.json`` to write once the rest of the folder has been checked (None when it stays
        as it is).
    """
    meta_path = out / "run.json"
    here = host()
    asked = threads or max(1, min(4, os.cpu_count() or 1))
    if meta_path.exists():
        meta = read_json(meta_path)
        if meta.get("mode") != mode:
            raise RunMismatchError("mode", f"{out} holds a {meta.get('mode')} run, not {mode}")
        if not isinstance(meta.get("config"), dict):
            raise CorruptFileError(meta_path, "records no configuration")
        grown = check_request(meta["config"], cfg, meta_path, extendable=("train.episodes",))
        schedule = int(meta.get("schedule_episodes", meta["config"].get("train", {}).get(
            "episodes", cfg.train.episodes)))
        hosts = meta.get("hosts") if isinstance(meta.get("hosts"), list) else []
        kept = meta.get("torch_threads")
        run_threads = kept if isinstance(kept, int) and kept >= 1 else asked
        # Provenance is recorded, never compared: a run resumed by another vgs (or MuJoCo,
        # torch) is kept, and the versions that resumed it are listed.
        made = meta.get("provenance") if isinstance(meta.get("provenance"), dict) else None
        resumed = meta.get("resumed_with") if isinstance(meta.get("resumed_with"), list) else []
        now = provenance()
        new_versions = now != made and now not in resumed
        if not grown and here in hosts and kept == run_threads and not new_versions \
                and "run_id" in meta:
            return schedule, run_threads, None
        meta.setdefault("run_id", uuid.uuid4().hex)  # (runs begun before it get one now)
        meta.update(config=to_dict(cfg), schedule_episodes=schedule, torch_threads=run_threads,
                    hosts=hosts + ([here] if here not in hosts else []))
        if new_versions:
            meta["resumed_with"] = [*resumed, now]
        return schedule, run_threads, meta
    leftovers = [n for n in ("checkpoint.pt", "episodes.csv") if (out / n).exists()]
    if leftovers:
        raise CorruptFileError(meta_path, f"is missing but {out} holds {', '.join(leftovers)}; "
                                          "restore it or train into a new folder")
    return cfg.train.episodes, asked, {
        "mode": mode, "run_id": uuid.uuid4().hex, "config": to_dict(cfg),
        "schedule_episodes": cfg.train.episodes,
        "torch_threads": asked, "git_revision": git_revision(),
        "python": sys.version.split()[0], "torch": torch.__version__, "hosts": [here],
        "provenance": provenance()}
