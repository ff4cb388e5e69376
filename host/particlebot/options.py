"""Numbers typed on the command line or in a radio URL, checked once where they are parsed."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

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
REACH_M = 1e4
"""No place (a lamp, an obstacle, where a swarm starts) lies further than this from the origin:
10 km is beyond any arena, and squares of such lengths stay exact enough."""
PLACE = Bounds(minimum=-REACH_M, maximum=REACH_M)
"""A coordinate in metres."""
LONGEST_S = 1e8
"""Simulated or recorded seconds (three years): nothing of a real swarm runs longer."""
DURATION = Bounds(above=0, maximum=LONGEST_S)
"""A length of time in seconds."""
SPAN_S = Bounds(minimum=0, maximum=LONGEST_S)
"""A length of time in seconds that may be 0."""
LENGTH_CM = Bounds(above=0, maximum=REACH_M * 100)
"""A size or height in centimetres (a camera's height, a particle's diameter)."""
DISTANCE_CM = Bounds(minimum=0, maximum=REACH_M * 100)
"""A distance in centimetres that may be 0 (a particle right under the lamp)."""
FRAME_RATE = Bounds(above=0, maximum=1000)
"""Frames per second: no camera of a swarm films faster than 1,000."""


def check_number(value: Any, bounds: Bounds = ANY, kind: str = "a number") -> float:
    """`value` as a float when it is a finite number within bounds (a bool is not a number);
    OptionError saying what was wanted otherwise. The one range check behind command-line
    options, scenario keys and settings, so that 1e308, inf, NaN and 10**400 meet the same
    answer wherever they come in."""
    try:
        number = float(value) if isinstance(value, int | float) else math.nan
    except OverflowError:  # an int beyond a float's range: 10**400
        number = math.copysign(math.inf, value)
    if isinstance(value, bool) or not math.isfinite(number) or not bounds.contains(number):
        shown = repr(value) if isinstance(value, str) else _short(value)
        raise OptionError(f"must be {bounds.describe(kind)}, not {shown}")
    return number


def check_fields(settings: object, ranges: Mapping[str, Bounds]) -> None:
    """Every named field of a settings object within its bounds; OptionError (a ValueError)
    that starts with the field's name, as scenario readers expect of settings' own checks."""
    for name, bounds in ranges.items():
        value = getattr(settings, name)
        kind = "a whole number" if isinstance(value, int) and not isinstance(value, bool) else ""
        try:
            check_number(value, bounds, kind or "a number")
        except OptionError as exc:
            raise OptionError(f"{name} {exc}") from None


def _short(value: Any) -> str:
    text = str(value)
    return text if len(text) <= 24 else f"{text[:10]}...({len(text)} digits)"


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
