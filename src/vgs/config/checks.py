"""Range checks the configuration dataclasses run in ``__post_init__``."""

from __future__ import annotations

import math
from typing import Any

from vgs.errors import ConfigError


def is_finite(value: Any) -> bool:
    """Whether ``value`` is a number a float can hold (an int of 400 digits is not)."""
    return isinstance(value, (int, float)) and abs(value) <= 1e300 and math.isfinite(value)


def shown(value: Any) -> str:
    """``repr(value)``, cut to 60 characters for a one-line message."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def check_positive(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (is_finite(value) and value > 0):
            raise ConfigError(f"{prefix}{name}", f"must be a positive number, got {shown(value)}")


def check_non_negative(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (is_finite(value) and value >= 0):
            raise ConfigError(f"{prefix}{name}", f"must be >= 0, got {shown(value)}")


def check_fraction(obj: Any, *names: str, prefix: str = "") -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
            raise ConfigError(f"{prefix}{name}", f"must lie in [0, 1], got {value!r}")
