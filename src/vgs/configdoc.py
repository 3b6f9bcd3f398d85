"""Every settable key of a configuration, its value and its documentation.

The documentation is read from the ``Attributes:`` sections of the dataclass docstrings in
:mod:`vgs.config` (Google style: ``name: text``, continuation lines indented further), so the
text lives in one place. ``vgs config`` prints what :func:`settings` returns; a test checks that
every key has a documentation.
"""

from __future__ import annotations

import ast
import inspect
import re
from dataclasses import dataclass, fields, is_dataclass
from typing import Any


@dataclass(frozen=True)
class Setting:
    """One settable key.

    Attributes:
        key: Dotted path, as ``--set KEY=VALUE`` takes it (``cell.peg.mass``).
        value: The value in the configuration.
        doc: Its documentation, whole (empty when the docstring has none).
    """

    key: str
    value: Any
    doc: str

    @property
    def summary(self) -> str:
        """The documentation's first sentence, without reStructuredText markup."""
        return first_sentence(plain(self.doc))


def field_docs(cls: type) -> dict[str, str]:
    """``{field name: text}`` from the ``Attributes:`` section of ``cls``'s docstring, each text
    on one line."""
    docs: dict[str, list[str]] = {}
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.strip() == "Attributes:")
    except StopIteration:
        return {}
    indent = len(lines[start]) - len(lines[start].lstrip())
    entry_indent = None
    current = None
    for line in lines[start + 1:]:
        if not line.strip():
            continue
        depth = len(line) - len(line.lstrip())
        if depth <= indent:  # the next section
            break
        if entry_indent is None:
            entry_indent = depth
        if depth == entry_indent:
            name, sep, text = line.strip().partition(":")
            current = name.strip() if sep else None
            if current is not None:
                docs[current] = [text.strip()]
        elif current is not None:
            docs[current].append(line.strip())
    return {name: " ".join(part for part in parts if part) for name, parts in docs.items()}


def plain(text: str) -> str:
    """``text`` without the reStructuredText markup of roles and literals."""
    return re.sub(r":[a-z]+:`([^`]*)`", r"\1", text).replace("``", "")


def first_sentence(text: str) -> str:
    """``text`` up to the end of its first sentence: a full stop outside parentheses followed by
    a capital letter (so ``i.e. within``, ``eq. 1`` and ``(2.3. A)`` do not end it)."""
    depth = 0
    for i, char in enumerate(text):
        if char in "([":
            depth += 1
        elif char in ")]":
            depth = max(0, depth - 1)
        elif (char == "." and depth == 0 and text[i + 1:i + 2] == " "
              and text[i + 2:i + 3].isupper()):
            return text[:i + 1]
    return text


def settings(cfg: Any, prefix: str = "") -> list[Setting]:
    """Every leaf field of the nested dataclass ``cfg``, in declaration order."""
    out = []
    docs = field_docs(type(cfg))
    for f in fields(cfg):
        value = getattr(cfg, f.name)
        if is_dataclass(value):
            out += settings(value, f"{prefix}{f.name}.")
        else:
            out.append(Setting(f"{prefix}{f.name}", value, docs.get(f.name, "")))
    return out


def as_text(value: Any) -> str:
    """``value`` as ``--set KEY=VALUE`` takes it: a string bare unless it reads as a literal."""
    if isinstance(value, str):
        try:
            ast.literal_eval(value)
        except (ValueError, SyntaxError):
            return value
    return repr(value)


def format_settings(items: list[Setting]) -> str:
    """One line per key: ``key = value  # first sentence of its doc``, keys aligned and values
    too (a value longer than 16 characters pushes its doc to the right)."""
    key_width = max(len(s.key) for s in items)
    values = [as_text(s.value) for s in items]
    value_width = min(16, max(len(v) for v in values))
    lines = []
    for s, value in zip(items, values, strict=True):
        line = f"{s.key:<{key_width}} = {value:<{value_width}}"
        lines.append(f"{line}  # {s.summary}" if s.summary else line.rstrip())
    return "\n".join(lines)
