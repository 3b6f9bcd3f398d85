"""``vgs status DIR``: how far a reproduction, training run or evaluation has got.

Reads only the files the runs write as they go (``episodes.csv`` of a training run, the
``journal.jsonl`` of an evaluation, ``reproduce.json``) and the metadata of a checkpoint
(:func:`vgs.checkpoint.read_meta`: its CRCs are checked, nothing in it is unpickled and torch is
not imported), so it is quick and safe to call while the run is working. A checkpoint that is
not in vgs's pickle-free format or is damaged, and a journal line that is not an episode row,
are refused with one line. It cannot tell a running job from a stopped one; it says when each
folder was last written. When one job's episodes come from several hosts (CPU model, MuJoCo
version), it says so.

Rates are per process: a training run is one process; an evaluation's ``s/episode`` is the
mean wall time of one episode in one worker, so N workers finish about N episodes in that time.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass
from pathlib import Path

from vgs import checkpoint
from vgs.columns import as_bool
from vgs.config import ExperimentConfig, from_dict
from vgs.errors import ConfigError, CorruptFileError
from vgs.runfolder.common import (
    check_belongs,
    check_table_digest,
    duration_text,
    engine_note,
    hosts_of,
    read_json,
    short_revision,
)
from vgs.runfolder.journal import read_journal
from vgs.runfolder.layout import eval_jobs, train_runs
from vgs.runfolder.schema import check_header

RATE_WINDOW = 50  # episodes behind a rate


@dataclass(frozen=True)
class Progress:
    """Progress of one job (a training run or an evaluation).

    Attributes:
        name: The job, as a path relative to the folder asked about.
        done: Episodes finished and written.
        total: Episodes planned.
        finished: Whether the job wrote its final files (``convergence.json``/``summary.json``).
        seconds_per_episode: Mean wall time of the last :data:`RATE_WINDOW` episodes of one
            process, or None before any.
        last_written: Seconds since the job last wrote a file, or None if it has not started.
        note: Anything else worth a line (checkpoint, exploration phase, success so far).
    """

    name: str
    done: int
    total: int
    finished: bool
    seconds_per_episode: float | None
    last_written: float | None
    note: str = ""

    @property
    def remaining_h(self) -> float | None:
        """Hours left for one process at the recent rate (None without a rate)."""
        if self.finished or self.seconds_per_episode is None:
            return None
        return max(self.total - self.done, 0) * self.seconds_per_episode / 3600.0

    def line(self) -> str:
        """Name, count, state and rate on one line; the note, if any, indented below."""
        if self.finished:
            state = "done"
        elif self.last_written is None:
            state = "not started"
        else:
            state = f"last written {_ago(self.last_written)} ago"
        parts = [f"{self.name:<34} {self.done:>5}/{self.total:<5} {state}"]
        if self.seconds_per_episode is not None and not self.finished:
            parts.append(f"{self.seconds_per_episode:.1f} s/episode, "
                         f"{duration_text(3600.0 * (self.remaining_h or 0.0))} left at that "
                         "rate")
        text = "; ".join(parts)
        return f"{text}\n    {self.note}" if self.note and not self.finished else (
            f"{text}; {self.note}" if self.note else text)


def _ago(seconds: float) -> str:
    return duration_text(seconds)


def _age(*paths: Path) -> float | None:
    mtimes = [p.stat().st_mtime for p in paths if p.exists()]
    return time.time() - max(mtimes) if mtimes else None


def _mean(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def train_progress(folder: Path, name: str | None = None, total: int | None = None
                   ) -> Progress:
    """Progress of a training run folder (``run.json``, ``episodes.csv``).

    Args:
        folder: The training run's folder.
        name: Name to show (default: the folder's name).
        total: Planned episodes of a run a reproduction plans; its folder may not exist yet.

    Raises:
        ConfigError: If ``folder`` does not exist and no ``total`` plans it.
    """
    name = name or folder.name
    meta_path, table = folder / "run.json", folder / "episodes.csv"
    if not meta_path.exists():
        if folder.exists():
            return Progress(name, 0, total or 0, False, None, None, "no run.json")
        if total is not None:
            return Progress(name, 0, total, False, None, None)
        raise ConfigError("dir", f"{folder} does not exist")
    meta = read_json(meta_path)
    cfg = recorded_config(meta_path, meta.get("config"))
    total = cfg.train.episodes
    rows: list[dict[str, str]] = []
    if table.exists():
        try:
            text = checkpoint.read_regular(table, checkpoint.MAX_JOURNAL_BYTES).decode("utf-8")
            reader = csv.DictReader(io.StringIO(text, newline=""))
            rows = [r for r in reader if r.get("wall_s") is not None]
        except (UnicodeDecodeError, csv.Error) as exc:
            raise CorruptFileError(table, f"cannot be read ({exc})") from None
        if text:  # (the table's schema: vgs.runfolder.schema)
            check_header(list(reader.fieldnames or []), table, "train")
        for i, row in enumerate(rows):  # episodes 0, 1, ... in order, as a resume checks
            if row.get("episode") != str(i) or row.get("mode") != meta["mode"]:
                raise CorruptFileError(table, f"holds {row.get('mode')!r} episode "
                                              f"{str(row.get('episode'))[:20]!r} where the "
                                              f"{meta['mode']} run's episode {i} belongs",
                                       line=i + 2)
    ckpt = folder / "checkpoint.pt"
    saved = checkpoint.read_meta(ckpt) if ckpt.exists() else None  # refuses a bad one
    at = int(saved["episode"]) if saved else 0
    if saved is not None:
        check_belongs(saved.get("run"), meta, ckpt, meta_path)  # not another run's checkpoint
        check_table_digest(table, ckpt, saved)
    done = len(rows)
    if done < at:  # a resume refuses it too (vgs.runfolder.trainfolder.read_rows)
        raise CorruptFileError(table, f"holds {done} episodes but {ckpt.name} is at episode "
                                      f"{at}: the table is not the run's; restore it")
    # (a published copy keeps no checkpoint: its table tells)
    finished = (folder / "convergence.json").exists() and done >= total and (
        saved is None or at >= total)
    walls = [_number(r.get("wall_s")) for r in rows[-RATE_WINDOW:]]
    walls = [w for w in walls if w is not None]
    notes = []
    if not finished and done:
        notes.append(f"a restart resumes at episode {at}" if saved else "no checkpoint yet")
        if done < cfg.agent.random_episodes:
            notes.append(f"random exploration until episode {cfg.agent.random_episodes} "
                         "(the episodes after it also run the forward pass: slower)")
    hosts = meta.get("hosts") if isinstance(meta.get("hosts"), list) else []
    if len(hosts) > 1:
        names = hosts_of(hosts)
        notes.append(f"trained on {len(hosts)} hosts ({'; '.join(names)}): the same scene can "
                     "end differently on another CPU")
    if engine := engine_note(hosts):
        notes.append(engine)
    if rows:
        window = rows[-RATE_WINDOW:]
        grasp = sum(flag_count(r.get("grasp_success")) for r in window) / len(window)
        ok = sum(flag_count(r.get("assembly_success")) for r in window) / len(window)
        notes.append(f"last {len(window)}: grasp {grasp:.2f}, assembly {ok:.2f}")
    last = _age(table, meta_path, folder / "checkpoint.pt") if rows else None
    return Progress(name, done, total, finished, _mean(walls), last, "; ".join(notes))


def eval_progress(folder: Path, name: str | None = None, total: int | None = None) -> Progress:
    """Progress of an evaluation folder (``meta.json``, ``journal.jsonl``, ``summary.json``).

    Args:
        folder: The evaluation's output folder.
        name: Name to show (default: the folder's name).
        total: Planned episodes when the folder has no ``meta.json`` yet.
    """
    name = name or folder.name
    meta_path, journal = folder / "meta.json", folder / "journal.jsonl"
    if meta_path.exists():
        episodes = read_json(meta_path).get("episodes")
        if isinstance(episodes, bool) or not isinstance(episodes, int):
            raise CorruptFileError(meta_path, f"records {episodes!r} episodes")
        total = episodes
    by_index, _ = read_journal(journal)  # a line cut by a running writer is skipped
    rows = [by_index[i] for i in sorted(by_index)]
    done = len(rows)
    summary = folder / "summary.json"
    finished = summary.exists() and total is not None and done >= total
    notes = []
    if not meta_path.exists() and journal.exists():
        notes.append("no meta.json: the planned number of episodes is unknown (a resume with "
                     "the same command checks every row and writes it again)")
    if rows:
        ok = sum(bool(r["assembly_success"]) for r in rows)
        notes.append(f"assembled {ok}/{len(rows)}")
        if not finished and total is not None and done >= total:
            notes.append("all episodes in, tables written when the evaluation ends")
    hosts = hosts_of(rows)
    if len(hosts) > 1:
        notes.append(f"episodes from {len(hosts)} hosts ({'; '.join(hosts)}): the same scene "
                     "can end differently on another CPU")
    if engine := engine_note(rows):
        notes.append(engine)
    walls = [_number(r.get("wall_s")) for r in rows[-RATE_WINDOW:]]
    walls = [w for w in walls if w is not None]
    last = _age(journal, meta_path) if (rows or meta_path.exists()) else None
    return Progress(name, done, total or 0, finished, _mean(walls), last, "; ".join(notes))


def recorded_config(path: Path, data: object) -> ExperimentConfig:
    """The configuration ``data`` that the file ``path`` recorded (its ``config``).

    Raises:
        CorruptFileError: If it is no usable configuration.
    """
    try:
        return from_dict(ExperimentConfig, data)  # type: ignore[arg-type]
    except (TypeError, ValueError, AttributeError) as exc:
        raise CorruptFileError(path, f"records no usable configuration ({exc})") from None


def _number(value: object) -> float | None:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None
    return number if number == number else None


def flag_count(value: object) -> int:
    """A boolean cell of ``episodes.csv``: ``True``/``False`` (0/1 in tables written before
    booleans were stored as booleans); anything else counts 0."""
    return int(bool(as_bool(value)))


def folder_status(path: Path) -> list[tuple[str, list[Progress]]]:
    """Sections of progress lines for a reproduction, training run or evaluation folder.

    Returns:
        ``(section title, jobs)`` pairs: ``train``, ``evaluate`` and ``sweep`` for a
        reproduction; one section for a single run.

    Raises:
        ConfigError: If ``path`` is not one of the three kinds of folder.
    """
    if not path.is_dir():
        raise ConfigError("dir", f"{path} is not a folder")
    if (path / "reproduce.json").exists():
        meta = read_json(path / "reproduce.json")
        cfg = recorded_config(path / "reproduce.json", meta.get("config"))
        train = [train_progress(run.folder, str(run.folder.relative_to(path)),
                                total=cfg.train.episodes) for run in train_runs(cfg, path)]
        evaluate = [eval_progress(job.folder, str(job.folder.relative_to(path)),
                                  total=cfg.eval.episodes) for job in eval_jobs(cfg, path)]
        sections = [("train", train), ("evaluate", evaluate)]
        r = cfg.reproduce
        if r.sweep_offsets:
            sweep = path / "sweep"
            total = r.sweep_offsets * r.sweep_trials
            done = (path / "sweep" / "summary.json").exists()
            sections.append(("sweep", [Progress("sweep", total if done else 0, total, done, None,
                                                _age(sweep / "sweep.csv"))]))
        return sections
    if (path / "run.json").exists():
        return [("train", [train_progress(path)])]
    if (path / "meta.json").exists() or (path / "journal.jsonl").exists():
        return [("evaluate", [eval_progress(path)])]
    raise ConfigError("dir", f"{path} is not a reproduction (reproduce.json), training run "
                             "(run.json) or evaluation (meta.json) folder")


def format_status(path: Path) -> str:
    """The text ``vgs status`` prints."""
    lines = [f"{path}"]
    if (path / "reproduce.json").exists():
        meta = read_json(path / "reproduce.json")
        walls = ", ".join(f"{k} {duration_text(v)}"
                          for k, v in meta.get("stage_wall_s", {}).items())
        lines[0] += (f": {meta.get('profile')} profile, source "
                     f"{short_revision(meta.get('git_revision'))}")
        if walls:
            lines.append(f"stage wall times so far: {walls}")
    for title, jobs in folder_status(path):
        done = sum(job.finished for job in jobs)
        lines.append(f"{title} ({done}/{len(jobs)} done)")
        lines += ["  " + job.line() for job in jobs]
    if (path / "report.md").exists():
        lines.append(f"report: {path / 'report.md'} ({_ago(_age(path / 'report.md') or 0)} old)")
    elif (path / "reproduce.json").exists():
        lines.append("report: not written yet")
    return "\n".join(lines)
