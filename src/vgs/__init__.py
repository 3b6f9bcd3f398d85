"""vgs: visual grasping strategy for peg-in-hole assembly (reference implementation).

Importing :mod:`vgs` registers the Gymnasium environment ``vgs/GraspAssemble-v0``
(:mod:`vgs.envs`); the environment's modules, MuJoCo and torch are imported only when it is
made.
"""

__version__ = "0.1.0"

from vgs.envs import ENV_ID, register  # noqa: E402  (registers the environment)

__all__ = ["ENV_ID", "__version__", "register"]
