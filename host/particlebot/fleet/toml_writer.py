"""A small TOML writer for files people also read: comments, hex integers, tables in a fixed order.

Python reads TOML with the standard library (tomllib) but has no writer. The fleet file is a
handful of tables of integers, strings, datetimes and lists; a writer this size gives us what
a general library (tomli-w) does not: a comment at the top, PAN ids and hashes in hex, and the
order of keys as the caller lists them.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


@dataclass(frozen=True)
class Hex:
    """An integer written in hexadecimal with at least `digits` digits (TOML reads it as int)."""

    value: int
    digits: int = 1


Scalar = str | int | bool | float | Hex | dt.datetime
Value = Scalar | Sequence[Scalar]


@dataclass(frozen=True)
class Table:
    """`[name]` and its key/value pairs (None: left out); name is a dotted path of keys."""

    name: Sequence[str]
    values: Mapping[str, Value | None]


def dumps(
    tables: Iterable[Table], *, top: Mapping[str, Value | None] | None = None, comment: str = ""
) -> str:
    """The document: the comment (one `#` line per line), top-level keys, then each table."""
    lines = [f"# {line}".rstrip() for line in comment.splitlines()]
    if top:
        if lines:
            lines.append("")
        lines += _pairs(top)
    for table in tables:
        if lines:
            lines.append("")
        lines.append("[" + ".".join(key(part) for part in table.name) + "]")
        lines += _pairs(table.values)
    return "\n".join(lines) + "\n"


def key(name: str) -> str:
    return name if _BARE_KEY.fullmatch(name) else string(name)


def string(text: str) -> str:
    out = []
    for char in text:
        if char in _ESCAPES:
            out.append(_ESCAPES[char])
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\u{ord(char):04X}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def value(item: Value) -> str:
    if isinstance(item, bool):
        return "true" if item else "false"
    if isinstance(item, Hex):
        if item.value < 0:
            raise ValueError("hexadecimal TOML integers cannot be negative")
        return f"0x{item.value:0{item.digits}X}"
    if isinstance(item, int):
        return str(item)
    if isinstance(item, float):
        return repr(item)
    if isinstance(item, str):
        return string(item)
    if isinstance(item, dt.datetime):
        if item.tzinfo is None:
            raise ValueError("datetimes are written with their UTC offset")
        return item.isoformat()
    return "[" + ", ".join(value(element) for element in item) + "]"


def _pairs(values: Mapping[str, Value | None]) -> list[str]:
    return [f"{key(name)} = {value(item)}" for name, item in values.items() if item is not None]
