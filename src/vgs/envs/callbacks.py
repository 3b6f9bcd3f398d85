"""A Stable-Baselines3 callback that logs each finished episode's outcome from ``info["record"]``.

This module imports Stable-Baselines3 (the ``sb3`` extra); nothing else in vgs imports it, so
vgs runs without SB3. The scalars (:func:`episode_scalars`) are averaged over the episodes that
finished since the logger's last dump (``logger.record_mean``; PPO dumps once per rollout):

* ``vgs/grasp_success``: share of episodes whose grasp held (``grasp_success``);
* ``vgs/abs_grasp_offset_mm``: mean |``grasp_offset_mm``| [mm] of the held grasps;
* ``vgs/assembly_success``: share assembled (``assembly_success``), of the episodes that ran an
  assembly (not counted in grasp-only episodes, ``failure_reason`` ``no_assembly``);
* ``vgs/assembly_time_s``: mean ``assembly_time_s`` [s] of the successful assemblies.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback

PREFIX = "vgs/"


def episode_scalars(record: Mapping[str, Any]) -> dict[str, float]:
    """The logged scalars of one episode record (``info["record"]``; the columns of
    :mod:`vgs.columns`); a scalar that the episode did not measure is left out."""
    grasped = bool(record["grasp_success"])
    out = {"grasp_success": float(grasped)}
    offset = record.get("grasp_offset_mm")
    if grasped and offset is not None and math.isfinite(offset):
        out["abs_grasp_offset_mm"] = abs(float(offset))
    if grasped and record.get("failure_reason") != "no_assembly":
        out["assembly_success"] = float(bool(record["assembly_success"]))
        time_s = record.get("assembly_time_s")
        if record["assembly_success"] and time_s is not None and math.isfinite(time_s):
            out["assembly_time_s"] = float(time_s)
    return out


class EpisodeLogger(BaseCallback):
    """Logs :func:`episode_scalars` of every finished episode as ``vgs/<name>`` (module
    docstring): ``model.learn(..., callback=EpisodeLogger())``."""

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", ()):
            record = info.get("record")
            if record is not None:
                for key, value in episode_scalars(record).items():
                    self.logger.record_mean(PREFIX + key, value)
        return True
