"""Gymnasium environments; ``import vgs`` (or this package) registers ``vgs/GraspAssemble-v0``.

Registering names the entry point as a string, so neither MuJoCo nor torch is imported until
the environment is made.
"""

from __future__ import annotations

import gymnasium

ENV_ID = "vgs/GraspAssemble-v0"
ENTRY_POINT = "vgs.envs.grasp_assemble:GraspAssembleEnv"


def register() -> None:
    """Register :data:`ENV_ID` with Gymnasium (once)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point=ENTRY_POINT)


register()
