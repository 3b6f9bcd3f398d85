"""Typed project errors.

Every error a user can cause by bad input derives from :class:`VGSError`; the CLI turns it into a
one-line message and exit code 2.
"""

from __future__ import annotations


class VGSError(Exception):
    """Base class of all vgs errors."""


class ConfigError(VGSError, ValueError):
    """An invalid configuration value.

    Attributes:
        field: Dotted name of the offending field (for example ``peg.mass``).
        message: What is wrong with it.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}")


class SimulationError(VGSError, RuntimeError):
    """The physics became unstable (NaN, runaway penetration)."""
