"""Range checks the configuration dataclasses run in ``__post_init__``."""

from __future__ import annotations

import math
from typing import Any

from vgs.errors import ConfigError


def _positive(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ConfigError(f"{prefix}{name}", f"must be a positive number, got {value!r}")


def _non_negative(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise ConfigError(f"{prefix}{name}", f"must be >= 0, got {value!r}")


def _fraction(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
            raise ConfigError(f"{prefix}{name}", f"must lie in [0, 1], got {value!r}")
