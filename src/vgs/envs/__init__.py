"""Gymnasium environments; ``vgs/GraspAssemble-v0`` is registered on import of :mod:`vgs.envs`."""

from __future__ import annotations

import gymnasium

ENV_ID = "vgs/GraspAssemble-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="vgs.envs.grasp_assemble:GraspAssembleEnv")
