"""Commands repeated until each particle confirms them (START, STOP) and parameter queries."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

from particlebot.protocol import BROADCAST_ID, Message, Param, ParamResult, State

# Clock readings are ~1.7e9 s since the epoch, where a float's rounding is ~2e-7 s: a poll at
# exactly the time a copy is due must not miss it by a rounding error.
CLOCK_SLACK_S = 1e-6


def state_name(value: int) -> str:
    try:
        return State(value).name
    except ValueError:
        return f"?{value}"


def param_name(value: int) -> str:
    try:
        return Param(value).name
    except ValueError:
        return f"#{value}"


def result_name(value: int) -> str:
    try:
        return ParamResult(value).name
    except ValueError:
        return f"result {value}"


# What a person does about a refusal: SERVO_CAL_3 = 2000 lies inside 500..2500, so the reason
# (a table that would no longer rise) must be said, not only named.
REFUSAL_ADVICE: dict[int, str] = {
    ParamResult.BUSY: "STOP them first",
    ParamResult.OUT_OF_RANGE: "'params' lists the ranges",
    ParamResult.UNKNOWN_PARAM: "a firmware without this parameter",
    ParamResult.SERVO_TABLE_NOT_MONOTONIC: (
        "SERVO_CAL_0..8 must keep rising (or falling) from point to point: change the "
        "neighbouring points first"
    ),
    ParamResult.RADIUS_MIN_NOT_BELOW_MAX: "RADIUS_MIN_UM must stay below RADIUS_MAX_UM",
}


def result_text(value: int) -> str:
    """A result's name, and for a refusal what to do about it."""
    advice = REFUSAL_ADVICE.get(value)
    return result_name(value) + (f": {advice}" if advice else "")


def ids_text(ids: list[int] | set[int] | tuple[int, ...]) -> str:
    """Particle ids with runs shortened: "1-6, 9, 10"."""
    ordered = sorted(set(ids))
    parts: list[str] = []
    start = 0
    for index in range(1, len(ordered) + 1):
        if index == len(ordered) or ordered[index] != ordered[index - 1] + 1:
            first, last = ordered[start], ordered[index - 1]
            if last - first >= 2:
                parts.append(f"{first}-{last}")
            else:
                parts.extend(str(i) for i in range(first, last + 1))
            start = index
    return ", ".join(parts)


class Verdict(Enum):
    """How a campaign ended."""

    CONFIRMED = "confirmed"
    """Every particle expected answered that it obeyed, and the base station knew the swarm."""
    UNCONFIRMED = "unconfirmed"
    """Sent, but nobody can vouch for every particle: no particle confirmed, or the base station
    had not listened long enough to know who is out there (a STOP just after it started)."""
    FAILED = "failed"
    """Some particle expected did not confirm in time, or the command could not be sent."""
    SUPERSEDED = "superseded"
    """A newer command of the same kind replaced it."""


@dataclass
class Campaign:
    """A command broadcast until every targeted particle confirms it, or time runs out.

    802.15.4 broadcasts are not acknowledged, so the only proof a particle obeyed is a STATUS it
    sent afterwards. The command goes out once at each offset in `burst` (seconds after
    `started`). With the last of those copies, and then every `interval`, a round PINGs the
    particles still pending by id, a few at a time, so that their STATUS comes at once rather
    than with the next periodic one; a round after the burst repeats the command only if some
    pending particle `needs_command` (a particle's answer shows it missed it, or none came), or
    while `hold_until` has not come (STOP just after the base station started: particles it has
    not heard of yet may be out there, moving).

    `pending` and `confirmed` hold row keys (see particlebot.swarm.roster). Particles heard for
    the first time while the campaign runs join it (`join_new`). It succeeds only once nothing is
    pending, the burst is out, `hold_until` has passed and at least `required()` particles
    confirmed; with `known` False (a base station that cannot vouch for every particle), such an
    ending is UNCONFIRMED, never CONFIRMED.
    """

    name: str
    command: Message
    started: float
    burst: tuple[float, ...]
    interval: float
    deadline: float
    pending: set[str]
    confirms: Callable[[str, float], bool]
    """confirms(row key, since): the particle's latest answer shows it obeyed."""
    needs_command: Callable[[str, float], bool]
    """needs_command(row key, since): its answer shows it missed the command (or none came)."""
    required: Callable[[], int] = lambda: 0
    """How many particles must confirm at least (the largest group seen, for STOP)."""
    hold_until: float = 0.0
    known: Callable[[], bool] = lambda: True
    """Whether the base station knows every particle that may have to obey (see Verdict)."""
    join_new: bool = True
    confirmed: set[str] = field(default_factory=set)
    rounds: int = 0
    pings: dict[str, int] = field(default_factory=dict)
    """PINGs sent to each particle (by key)."""
    next_send: float = 0.0
    last_broadcast_ping: float = -1e18
    send_failures: int = 0
    done: bool = False
    verdict: Verdict | None = None
    """How it ended (None while it runs)."""
    outcome: str = ""
    finished_at: float | None = None

    @property
    def success(self) -> bool:
        """Whether it ended confirmed."""
        return self.verdict is Verdict.CONFIRMED

    @property
    def burst_sent(self) -> bool:
        return self.rounds >= len(self.burst)

    @property
    def timeout(self) -> float:
        return self.deadline - self.started


@dataclass
class ParamQuery:
    """A SET_PARAM or GET_PARAM waiting for its PARAM_VALUE answers. Particles that have not
    answered `first_wait` after it went out (a broadcast's answers come in random slots) are
    asked again by id, then every `retry_after`, up to `attempts` times in all; the answers are
    then summarised in one note rather than shown one line per particle."""

    kind: str  # "SET" or "GET"
    param: int
    value: int | None
    target: int
    started: float
    expected: set[int]
    attempts: int = 1
    first_wait: float = 2.0
    retry_after: float = 0.5
    asked: int = 1
    """Rounds sent so far (the first is the broadcast, or the one addressed to target)."""
    last_asked: float = 0.0
    replies: dict[int, tuple[int, int]] = field(default_factory=dict)
    """particle id -> (ParamResult, value)"""
    done: bool = False
    finished_at: float | None = None

    @property
    def next_ask(self) -> float:
        """When the particles that have not answered are asked again (or it concludes)."""
        wait = self.first_wait if self.asked == 1 else self.retry_after
        return self.last_asked + wait

    def accepts(self, sender: int, param: int) -> bool:
        return (
            not self.done
            and param == self.param
            and (self.target == BROADCAST_ID or self.target == sender)
        )

    @property
    def missing(self) -> list[int]:
        return sorted(self.expected - set(self.replies))

    @property
    def ok(self) -> bool:
        """Every particle asked answered OK."""
        return (
            bool(self.replies)
            and not self.missing
            and all(result == ParamResult.OK for result, _ in self.replies.values())
        )

    def head(self) -> str:
        name = param_name(self.param)
        head = f"{self.kind} {name}" + (f" = {self.value}" if self.kind == "SET" else "")
        if self.target != BROADCAST_ID:
            head = f"{head} to particle {self.target}"
        return head

    def summary(self, waited: float) -> str:
        """e.g. "SET CYCLE_STEPS = 300: 8/10 OK; BUSY: 3, 7 (STOP them first)"."""
        head = self.head()
        missing = self.missing
        if not self.replies:
            if self.target != BROADCAST_ID:
                return f"{head}: no answer within {waited:g} s"
            return f"{head}: no particle answered within {waited:g} s"
        parts: list[str] = []
        if self.kind == "SET":
            ok = [i for i, (result, _) in self.replies.items() if result == ParamResult.OK]
            parts.append(f"{len(ok)}/{len(self.expected | set(self.replies))} OK")
            for result in sorted({r for r, _ in self.replies.values()} - {ParamResult.OK}):
                ids = [i for i, (r, _) in self.replies.items() if r == result]
                advice = REFUSAL_ADVICE.get(result)
                parts.append(f"{result_name(result)}: {ids_text(ids)}")
                if advice:
                    parts[-1] += f" ({advice})"
        else:
            by_value: dict[tuple[int, int], list[int]] = {}
            for particle, answer in self.replies.items():
                by_value.setdefault(answer, []).append(particle)
            for (result, value), ids in sorted(by_value.items(), key=lambda item: -len(item[1])):
                shown = str(value) if result == ParamResult.OK else result_name(result)
                parts.append(f"{shown} on {ids_text(ids)}")
        if missing:
            parts.append(f"no answer from {ids_text(missing)}")
        return f"{head}: " + "; ".join(parts)
