"""What the Swarm API hands back: particles as heard, typed reports, and the errors it raises."""

from __future__ import annotations

from dataclasses import dataclass

from particlebot.errors import ParticlebotError
from particlebot.protocol import Method, Param, ParamResult, State, Status
from particlebot.swarm.campaigns import Verdict, ids_text


@dataclass(frozen=True)
class Particle:
    """One particle as the base station knows it at one moment."""

    id: int
    radio: str | None
    """The radio address it sends from, where the radio tells (API-mode XBee, simulations)."""
    state: State | None
    """From its latest STATUS; None before one came."""
    s_n: int | None
    """Its place in the wave (1 = nearest the light) in its latest run; None before one."""
    run_id: int | None
    intensity: int | None
    last_heard: float
    """The radio's clock (seconds since the epoch; simulated on simulated radios)."""
    flags: tuple[str, ...]
    """What a person should look at: DUPLICATE, SILENT 9s, NOT IN FLEET, RESET in run 3, ..."""
    status: Status | None
    """Its latest STATUS, every field."""


@dataclass(frozen=True)
class Unconfirmed:
    """A particle that did not confirm a command, and why."""

    particle: int
    reason: str

    def __str__(self) -> str:
        return f"{self.particle}: {self.reason}"


@dataclass(frozen=True)
class Reply:
    """One particle's answer to a SET or GET."""

    particle: int
    result: ParamResult
    value: int
    """The value it holds now."""


@dataclass(frozen=True)
class ParamReport:
    """The answers to a SET_PARAM (value set) or GET_PARAM (value None)."""

    param: Param
    value: int | None
    replies: dict[int, Reply]
    """By particle id."""
    missing: tuple[int, ...]
    """Asked, never answered (after every retry)."""
    text: str
    """The one-line summary the console shows."""

    @property
    def ok(self) -> bool:
        """Every particle asked answered, all OK."""
        return (
            bool(self.replies)
            and not self.missing
            and all(reply.result == ParamResult.OK for reply in self.replies.values())
        )

    @property
    def values(self) -> dict[int, int]:
        """What each particle that answered OK holds."""
        return {
            particle: reply.value
            for particle, reply in self.replies.items()
            if reply.result == ParamResult.OK
        }

    @property
    def unconfirmed(self) -> tuple[Unconfirmed, ...]:
        refused = [
            Unconfirmed(particle, f"answered {reply.result.name}")
            for particle, reply in sorted(self.replies.items())
            if reply.result != ParamResult.OK
        ]
        silent = [Unconfirmed(particle, "no answer") for particle in self.missing]
        return tuple(sorted(refused + silent, key=lambda item: item.particle))


@dataclass(frozen=True)
class Run:
    """A START every particle present confirmed."""

    run_id: int
    method: Method
    cycle_steps: int
    wave_size: int
    update_interval_s: int
    phototaxis: bool
    started_at: float
    """When START first went out (the radio's clock)."""
    confirmed_at: float
    particles: tuple[int, ...]
    """Who confirmed it."""


@dataclass(frozen=True)
class StopReport:
    """What came of a STOP: confirmed by every particle expected, or who did not, and why."""

    confirmed: bool
    stopped: tuple[int, ...]
    """Particles whose STATUS after the STOP shows them IDLE or DONE."""
    unconfirmed: tuple[Unconfirmed, ...]
    never_heard: int
    """Particles known to exist (the largest group seen together) that never answered at all."""
    seconds: float
    """From the first STOP to the outcome."""
    text: str
    """The one-line outcome the console shows."""
    verdict: Verdict = Verdict.FAILED
    """CONFIRMED (then `confirmed`), UNCONFIRMED (sent, but nobody can vouch for every
    particle: nobody confirmed, or the base station had not listened long enough), or FAILED."""

    def __str__(self) -> str:
        return self.text


class SwarmError(ParticlebotError):
    """Something the swarm could not do; the message says what, and what to try."""


class ParticlesMissing(SwarmError):  # noqa: N818 (reads as what happened, like TimeoutError)
    """wait_for() ran out of time before the particles asked for answered."""

    def __init__(self, message: str, heard: tuple[int, ...], missing: tuple[int, ...]) -> None:
        super().__init__(message)
        self.heard = heard
        self.missing = missing
        """Ids that were asked for by name and never answered (empty when a count was asked)."""


class NotConfirmed(SwarmError):  # noqa: N818
    """A command some particle did not confirm (START, SET, SET_ID); `unconfirmed` says who."""

    def __init__(self, message: str, unconfirmed: tuple[Unconfirmed, ...]) -> None:
        super().__init__(message)
        self.unconfirmed = unconfirmed


class IdInUse(SwarmError):  # noqa: N818
    """SET_ID to an id the fleet lists or another particle answers with (force=True overrides)."""


def not_confirmed_text(what: str, unconfirmed: tuple[Unconfirmed, ...]) -> str:
    """e.g. "START not confirmed by 3, 7: 3: no STATUS since the command; 7: reports run 2"."""
    ids = ids_text([item.particle for item in unconfirmed])
    reasons = "; ".join(str(item) for item in unconfirmed)
    return f"{what} not confirmed by particle(s) {ids}: {reasons}"
