"""Numbers typed on the command line or in a radio URL, checked once where they are parsed."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from dataclasses import dataclass

from particlebot.errors import ParticlebotError


class OptionError(ParticlebotError, ValueError):
    """A number that is not one, or out of its range; the message says what was expected."""


@dataclass(frozen=True)
class Bounds:
    """Which numbers an option takes. NaN and infinities never pass (a NaN compares false with
    every bound and would slip through a plain range check, then hang a loop waiting for it);
    a word such as `max` may stand for infinity where the option means "no limit"."""

    minimum: float | None = None
    above: float | None = None
    maximum: float | None = None
    below: float | None = None
    words: tuple[tuple[str, float], ...] = ()

    def contains(self, value: float) -> bool:
        return not (
            math.isnan(value)
            or (self.minimum is not None and value < self.minimum)
            or (self.above is not None and value <= self.above)
            or (self.maximum is not None and value > self.maximum)
            or (self.below is not None and value >= self.below)
        )

    def describe(self, kind: str) -> str:
        """e.g. "a number > 0 or max", "a whole number 1..200"."""
        if self.minimum is not None and self.maximum is not None:
            text = f"{kind} {_g(self.minimum)}..{_g(self.maximum)}"
        else:
            limits = []
            if self.minimum is not None:
                limits.append(f">= {_g(self.minimum)}")
            if self.above is not None:
                limits.append(f"> {_g(self.above)}")
            if self.maximum is not None:
                limits.append(f"<= {_g(self.maximum)}")
            if self.below is not None:
                limits.append(f"< {_g(self.below)}")
            text = " ".join([kind, " and ".join(limits)]).strip()
        return " or ".join([text, *(word for word, _ in self.words)])


def _g(value: float) -> str:
    return f"{value:g}"


ANY = Bounds()
POSITIVE = Bounds(above=0)
NON_NEGATIVE = Bounds(minimum=0)
SWITCH = Bounds(minimum=0, maximum=1)
"""0 off, 1 on."""
SPEED = Bounds(above=0, words=(("max", math.inf),))
"""Times real time; `max` runs as fast as the machine allows."""


def parse_float(text: str, bounds: Bounds = ANY) -> float:
    """A finite number within bounds (or one of its words); OptionError says what was wanted."""
    word = dict(bounds.words).get(text.strip().lower())
    if word is not None:
        return word
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or not bounds.contains(value):
        raise OptionError(f"must be {bounds.describe('a number')}, not '{text}'")
    return value


def parse_int(text: str, bounds: Bounds = ANY) -> int:
    """A whole number (decimal, or 0x.. hex) within bounds; OptionError says what was wanted."""
    value: int | None
    try:
        value = int(text, 0)
    except ValueError:
        value = None
    if value is None or not bounds.contains(value):
        raise OptionError(f"must be {bounds.describe('a whole number')}, not '{text}'")
    return value


def float_arg(bounds: Bounds = ANY) -> Callable[[str], float]:
    """An argparse `type=` that takes numbers within bounds."""

    def parse(text: str) -> float:
        try:
            return parse_float(text, bounds)
        except OptionError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse


def int_arg(bounds: Bounds = ANY) -> Callable[[str], int]:
    """An argparse `type=` that takes whole numbers within bounds."""

    def parse(text: str) -> int:
        try:
            return parse_int(text, bounds)
        except OptionError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse
