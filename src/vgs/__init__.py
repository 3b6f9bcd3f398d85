"""vgs: visual grasping strategy for peg-in-hole assembly (reference implementation).

Importing :mod:`vgs.envs` registers the Gymnasium environment ``vgs/GraspAssemble-v0``.
"""

__version__ = "0.1.0"
