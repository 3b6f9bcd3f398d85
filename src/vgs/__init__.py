"""vgs: visual grasping strategy for peg-in-hole assembly (reference implementation)."""

__version__ = "0.1.0"
