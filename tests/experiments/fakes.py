"""A stand-in for the physics: episodes that cost milliseconds, for tests of the run machinery
(journals, checkpoints, resume, refusals) rather than of the cell.

:class:`FakeRunner` has the interface of :class:`vgs.assembly.episode.EpisodeRunner`: it draws a
peg-shaped block on an empty heightmap from the episode seed, asks the policy for its grasp and
makes up a record that depends only on the seed, the peg and the grasp; so tables are
deterministic, and a policy (or network) that changes its grasp changes the rows.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from vgs.assembly.record import EpisodeRecord
from vgs.config import ExperimentConfig, override, profile
from vgs.sim.camera import Heightmap

SIZE = 64


def tiny_config(train_episodes: int = 6, eval_episodes: int = 8) -> ExperimentConfig:
    """The smoke profile on a 64 px heightmap."""
    cfg = profile("smoke")
    for path, value in (("cell.camera.size", SIZE), ("cell.camera.pixel_size", 0.007),
                        ("train.episodes", train_episodes), ("train.checkpoint_every", 2),
                        ("agent.random_episodes", 2), ("eval.episodes", eval_episodes)):
        cfg = override(cfg, path, value)
    return cfg


# The command-line flags giving tiny_config() (defaults).
CONFIG_FLAGS = ["--profile", "smoke", "--set", f"cell.camera.size={SIZE}", "--set",
             "cell.camera.pixel_size=0.007", "--set", "train.checkpoint_every=2", "--set",
             "agent.random_episodes=2", "--set", "train.episodes=6", "--set", "eval.episodes=8"]
CLI_FLAGS = [*CONFIG_FLAGS, "--no-progress"]


class FakeRunner:
    """:class:`vgs.assembly.episode.EpisodeRunner` without physics (module docstring)."""

    delay = 0.0  # seconds each episode sleeps (so that a kill can land inside a run)

    def __init__(self, cfg: ExperimentConfig) -> None:
        self.cfg = cfg

    def observe(self, seed: int, peg: Any = None) -> Heightmap:
        rng = np.random.default_rng([seed, 99])
        n = self.cfg.cell.camera.size
        depth = np.zeros((n, n), np.float32)
        r, c = (int(v) for v in rng.integers(n // 4, 3 * n // 4, size=2))
        depth[r - 2:r + 3, c - 7:c + 8] = 0.03
        color = np.full((n, n, 3), 90, np.uint8)
        color[depth > 0] = (200, 120, 40)
        return Heightmap(color, depth, (0.35, -0.2), self.cfg.cell.camera.pixel_size)

    def run(self, seed: int, policy: Any, peg: Any = None, trace: bool = False,
            assemble: bool = True, time_limit: float | None = None
            ) -> tuple[EpisodeRecord, None, Heightmap]:
        peg = peg or self.cfg.cell.peg
        hm = self.observe(seed)
        command = policy(hm)
        if self.delay:
            time.sleep(self.delay)
        u = (int(abs(command.x) * 1e4) + int(abs(command.y) * 1e4) + seed) % 7
        ok = u > 2
        record = EpisodeRecord(seed=seed, peg_mass=peg.mass, peg_length=peg.length,
                               grasp_success=u != 0, grasp_offset=(u - 3) * 0.004,
                               success=ok, failure_reason="" if ok else "timeout:align",
                               assembly_time=20.0 + 3.0 * u * peg.mass)
        if record.grasp_success and not assemble:  # as EpisodeRunner.run's shortcuts
            record.success, record.failure_reason = False, "no_assembly"
            record.assembly_time = float("nan")
        elif record.grasp_success and time_limit is not None \
                and record.assembly_time > time_limit:
            record.success, record.failure_reason = False, "cutoff:align"
        return record, None, hm


def install(delay: float = 0.0) -> None:
    """Put :class:`FakeRunner` in place of the physics for training and evaluation."""
    from vgs.experiments import train
    from vgs.rollout import episodepool

    FakeRunner.delay = delay
    train.EpisodeRunner = FakeRunner  # type: ignore[misc]
    episodepool.EpisodeRunner = FakeRunner  # type: ignore[misc]


def run_cli(argv: list[str], delay: float) -> None:
    """Child process body: the ``vgs`` command on the fake physics (killed from outside)."""
    import sys

    install(delay)
    from vgs.cli import main

    sys.argv = ["vgs", *argv]  # as the command line runs it (vgs.cli.main's signal handling)
    sys.exit(main())


def use_fake_physics(monkeypatch: Any) -> None:
    """In this process: :class:`FakeRunner` for training and evaluation, one core (undone by
    pytest's ``monkeypatch`` after the test)."""
    from vgs.experiments import train
    from vgs.rollout import episodepool

    monkeypatch.setattr(train, "EpisodeRunner", FakeRunner)
    monkeypatch.setattr(episodepool, "EpisodeRunner", FakeRunner)
    monkeypatch.setattr("os.cpu_count", lambda: 1)


def vgs(capsys: Any, *argv: str) -> tuple[int, list[str]]:
    """Exit code of ``vgs ARGV`` in this process and the stderr lines that are not progress
    logs."""
    from vgs.cli import main

    capsys.readouterr()
    rc = main(list(argv))
    err = capsys.readouterr().err
    return rc, [line for line in err.splitlines()
                if not line.startswith(("train vgs", "train baseline", "eval "))]


def one_line(rc: int, lines: list[str], *words: str) -> None:
    """The command failed with exit code 2 and one ``vgs: error:`` line holding ``words``."""
    assert rc == 2, lines
    assert len(lines) == 1 and lines[0].startswith("vgs: error: "), lines
    for word in words:
        assert word in lines[0], lines
