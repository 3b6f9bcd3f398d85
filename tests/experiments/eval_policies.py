"""User policies (``module:function`` specs) for the evaluation tests: one that raises and two
that kill their worker process. Imported by spawned workers through ``sys.path``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from vgs.rollout.policies import CenterPolicy, Decision


class Raising:
    label = "raising"

    def __call__(self, hm: Any, rng: Any) -> Decision:
        raise RuntimeError("policy exploded on purpose")


class CrashOnce:
    """Kills its process the first time (marker file absent), then grasps at the centre."""

    label = "crash_once"

    def __call__(self, hm: Any, rng: Any) -> Decision:
        marker = Path(os.environ["VGS_TEST_MARKER"])
        if not marker.exists():
            marker.write_text("crashed")
            os._exit(3)
        return CenterPolicy()(hm, rng)


class CrashAlways:
    label = "crash_always"

    def __call__(self, hm: Any, rng: Any) -> Decision:
        os._exit(3)


def raising(cfg: Any) -> Raising:
    return Raising()


def crash_once(cfg: Any) -> CrashOnce:
    return CrashOnce()


def crash_always(cfg: Any) -> CrashAlways:
    return CrashAlways()
