"""Checked values for scenario readers: numbers, pairs, names and settings tables, each error one
line that names the file, the line and the key (and the key meant, when one is misspelt)."""

from __future__ import annotations

import difflib
import math
import typing
from collections.abc import Iterable, Mapping
from dataclasses import fields, is_dataclass
from enum import Enum
from typing import Any, TypeVar

from particlebot.options import REACH_M, Bounds, OptionError, check_number
from particlebot.sim.scenarios.scenario import ScenarioError, SourceMap

T = TypeVar("T")
E = TypeVar("E", bound=Enum)


def suggestion(key: str, known: Iterable[str]) -> str:
    """' (did you mean 'x'?)' for a near miss among the known keys, else ''."""
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.6)
    if not close:
        lowered = {k.lower(): k for k in known}
        if key.lower() in lowered:
            close = [lowered[key.lower()]]
    return f" (did you mean '{close[0]}'?)" if close else ""


class Fields:
    """Reads typed values out of a parsed table, raising ScenarioError with the key's line."""

    def __init__(self, source: SourceMap) -> None:
        self.source = source

    def fail(self, key: str, message: str) -> ScenarioError:
        return self.source.error(key, message)

    def only(self, table: Mapping[str, Any], prefix: str, allowed: Iterable[str]) -> None:
        """Every key of the table is one of `allowed`; a misspelt one gets a suggestion."""
        known = list(allowed)
        for key in table:
            if key not in known:
                raise self.fail(
                    _join(prefix, key),
                    f"unknown key{suggestion(key, known)}; keys here: " + ", ".join(known),
                )

    def table(self, parent: Mapping[str, Any], key: str, prefix: str = "") -> dict[str, Any]:
        value = parent.get(key, {})
        if not isinstance(value, dict):
            raise self.fail(_join(prefix, key), "must be a table ([...] section)")
        return value

    def number(
        self,
        table: Mapping[str, Any],
        key: str,
        prefix: str,
        default: float,
        *,
        minimum: float | None = None,
        above: float | None = None,
        maximum: float | None = None,
    ) -> float:
        if key not in table:
            return default
        return self.check_number(
            table[key], _join(prefix, key), minimum=minimum, above=above, maximum=maximum
        )

    def place(self, table: Mapping[str, Any], key: str, prefix: str, default: float) -> float:
        """A coordinate (m) within REACH_M of the origin."""
        return self.number(table, key, prefix, default, minimum=-REACH_M, maximum=REACH_M)

    def check_number(
        self,
        value: Any,
        key: str,
        *,
        minimum: float | None = None,
        above: float | None = None,
        maximum: float | None = None,
    ) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"must be a number, not {_show(value)}")
        try:
            return check_number(value, Bounds(minimum=minimum, above=above, maximum=maximum))
        except OptionError as exc:
            raise self.fail(key, str(exc)) from None

    def integer(
        self,
        table: Mapping[str, Any],
        key: str,
        prefix: str,
        default: int,
        *,
        minimum: int = 0,
        maximum: int | None = None,
    ) -> int:
        if key not in table:
            return default
        return self.check_integer(table[key], _join(prefix, key), minimum=minimum, maximum=maximum)

    def check_integer(
        self, value: Any, key: str, *, minimum: int | None = 0, maximum: int | None = None
    ) -> int:
        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"must be a whole number, not {_show(value)}")
        try:
            check_number(value, Bounds(minimum=minimum, maximum=maximum), "a whole number")
        except OptionError as exc:
            raise self.fail(key, str(exc)) from None
        return value

    def boolean(self, table: Mapping[str, Any], key: str, prefix: str, default: bool) -> bool:
        if key not in table:
            return default
        value = table[key]
        if not isinstance(value, bool):
            raise self.fail(_join(prefix, key), f"must be true or false, not {_show(value)}")
        return value

    def string(self, table: Mapping[str, Any], key: str, prefix: str, default: str) -> str:
        if key not in table:
            return default
        value = table[key]
        if not isinstance(value, str) or not value.strip():
            raise self.fail(_join(prefix, key), f"must be a non-empty string, not {_show(value)}")
        return value

    def choice(
        self, table: Mapping[str, Any], key: str, prefix: str, kind: type[E], default: E
    ) -> E:
        if key not in table:
            return default
        value = table[key]
        names = [member.value for member in kind]
        if not isinstance(value, str) or value not in names:
            raise self.fail(
                _join(prefix, key),
                f"must be one of {', '.join(map(repr, names))}, not {_show(value)}"
                + (suggestion(value, names) if isinstance(value, str) else ""),
            )
        return kind(value)

    def numbers(
        self, table: Mapping[str, Any], key: str, prefix: str, length: int
    ) -> tuple[float, ...] | None:
        """A list of exactly `length` coordinates (within REACH_M), or None when the key is
        absent."""
        if key not in table:
            return None
        value = table[key]
        where = _join(prefix, key)
        if not isinstance(value, list):
            raise self.fail(where, f"must be a list of {length} numbers, not {_show(value)}")
        if len(value) != length:
            raise self.fail(where, f"must be a list of {length} numbers, not {len(value)}")
        return tuple(self.check_number(v, where, minimum=-REACH_M, maximum=REACH_M) for v in value)

    def settings(self, cls: type[T], table: Mapping[str, Any], prefix: str, base: T) -> T:
        """A frozen settings dataclass from `base` with the table's keys replaced; the keys are
        its field names, checked against the field's type (int, float, bool, an enum or a
        nested settings table)."""
        assert is_dataclass(cls)
        hints = typing.get_type_hints(cls)
        names = [f.name for f in fields(cls)]
        self.only(table, prefix, names)
        values: dict[str, Any] = {}
        for name in names:
            if name not in table:
                continue
            hint = hints[name]
            where = _join(prefix, name)
            raw = table[name]
            if isinstance(hint, type) and is_dataclass(hint):
                if not isinstance(raw, dict):
                    raise self.fail(where, "must be a table")
                values[name] = self.settings(hint, raw, where, getattr(base, name))
            elif isinstance(hint, type) and issubclass(hint, Enum):
                values[name] = self.enum_value(hint, raw, where)
            elif hint is bool:
                if not isinstance(raw, bool):
                    raise self.fail(where, f"must be true or false, not {_show(raw)}")
                values[name] = raw
            elif hint is int:
                values[name] = self.check_integer(raw, where, minimum=None)
            else:
                values[name] = self.check_number(raw, where)
        current = {f.name: getattr(base, f.name) for f in fields(cls)}
        current.update(values)
        try:
            return cls(**current)
        except ValueError as exc:
            message = str(exc)
            # The settings' own checks name the field first; point at its line.
            named = [n for n in names if message.startswith(n) or f" {n} " in f" {message} "]
            if named and message.startswith(f"{named[0]} must "):
                message = message.removeprefix(f"{named[0]} ")  # the key says it already
            raise self.fail(_join(prefix, named[0]) if named else prefix, message) from None

    def enum_value(self, kind: type[E], raw: Any, where: str) -> E:
        """An enum member by name (any case), by its first letter for the SI's methods A-D,
        or by value."""
        members = list(kind)
        if isinstance(raw, str):
            text = raw.strip().upper()
            for member in members:
                if member.name == text:
                    return member
            letters = {chr(ord("A") + i): m for i, m in enumerate(members)}
            if len(text) == 1 and text in letters:
                return letters[text]
        elif isinstance(raw, int) and not isinstance(raw, bool):
            for member in members:
                if member.value == raw:
                    return member
        names = ", ".join(m.name for m in members)
        letters_too = f" (or A-{chr(ord('A') + len(members) - 1)})" if len(members) <= 26 else ""
        raise self.fail(where, f"must be one of {names}{letters_too}, not {_show(raw)}")


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _show(value: Any) -> str:
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "a list"
    return str(value)
