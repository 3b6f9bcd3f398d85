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

    def __reduce__(self) -> tuple[type, tuple[str, str]]:  # survives a process pool
        return type(self), (self.field, self.message)


class SimulationError(VGSError, RuntimeError):
    """The physics became unstable (NaN, runaway penetration)."""


class CorruptFileError(VGSError):
    """A file of a run folder that cannot be read, or holds what the run did not write.

    Attributes:
        path: The file.
        line: 1-based line number, or None for the whole file.
        message: What is wrong.
    """

    def __init__(self, path: object, message: str, line: int | None = None) -> None:
        self.path = str(path)
        self.line = line
        self.message = message
        where = self.path if line is None else f"{self.path}:{line}"
        super().__init__(f"{where}: {message}")

    def __reduce__(self) -> tuple[type, tuple[str, str, int | None]]:
        return type(self), (self.path, self.message, self.line)


class CheckpointError(CorruptFileError):
    """A checkpoint that is missing, damaged, or not in vgs's pickle-free format."""


class RunMismatchError(ConfigError):
    """A request that differs from the run already in the output folder (``field`` names the
    first configuration field that differs)."""


class FolderBusyError(VGSError):
    """Another vgs process holds the output folder's lock."""


class EpisodeError(VGSError):
    """An exception inside an episode (a bug, not a result): the run stops, naming the episode
    and the error; the rows already journaled are kept."""


class InterruptedBySignal(KeyboardInterrupt):
    """SIGTERM (or SIGHUP) received: handled like Ctrl-C, ending with exit code 128 + signal.

    Attributes:
        signum: The signal's number.
    """

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(f"signal {signum}")
