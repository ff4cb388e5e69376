"""Who is in the swarm: a row per particle heard or expected, and what tells two particles apart."""

from __future__ import annotations

from dataclasses import dataclass, field

from particlebot.protocol import DEFINITION_HASH, UNASSIGNED_ID, State, Status
from particlebot.resets import UPTIME_WRAP_MS, reset_between

# STATUS comes every STATUS_PERIOD_MS (2 s by default, +-25 %): three missed ones mean trouble.
SILENT_AFTER_S = 6.5
RECENT_S = 300.0
"""A particle heard this recently is expected to answer a STOP (one heard longer ago may have been
switched off)."""
STOPPED_STATES = frozenset({State.IDLE, State.DONE})
OBEYED_STOP_STATES = frozenset({State.STOPPING, State.IDLE, State.DONE})
MOVING_STATES = frozenset({State.ESTIMATING, State.WAITING, State.CYCLING, State.PAUSED})
"""A particle in one of these is in a run: quitting or restarting would leave it, or cut it."""
RUN_STATES = MOVING_STATES | {State.STOPPING}

# One particle's uptime advances with the receive clock; a STATUS waits a little in radio buffers
# (a second at most on a busy 9600-baud link), and the particle's ceramic resonator is good to
# 0.5 %. Two particles answering as one id show two clocks much further apart than that.
CLOCK_SLACK_MS = 1500
CLOCK_DRIFT = 0.02


def two_clocks(before: Status, before_at: float, after: Status, after_at: float) -> str | None:
    """Why two STATUS reports under one id cannot come from one particle (None if they can).

    A particle's uptime grows as fast as time passes, and starts again near 0 when it resets,
    with its reset counter one up. A second particle with the same id has its own uptime and
    counter: the reports then jump between two clocks, which this catches at the first jump."""
    if before.uptime_ms > UPTIME_WRAP_MS - 600_000:
        return None  # near the u32 wrap a jump back is the wrap
    elapsed_ms = max(0.0, (after_at - before_at) * 1000)
    slack = CLOCK_SLACK_MS + CLOCK_DRIFT * elapsed_ms
    if reset_between(before, after):
        if after.resets < before.resets:
            return f"its reset counter went back from {before.resets} to {after.resets}"
        if after.uptime_ms > elapsed_ms + slack:
            return (
                f"its uptime jumped from {before.uptime_ms / 1000:.0f} s to "
                f"{after.uptime_ms / 1000:.0f} s in {elapsed_ms / 1000:.0f} s"
            )
        return None
    if after.uptime_ms - before.uptime_ms > elapsed_ms + slack:
        return (
            f"its uptime jumped from {before.uptime_ms / 1000:.0f} s to "
            f"{after.uptime_ms / 1000:.0f} s in {elapsed_ms / 1000:.0f} s"
        )
    return None


SEQ_WINDOW_S = 20.0
"""A particle sends under 3 frames a second at most (an estimation round's broadcasts and its
STATUS): within this long, its 8-bit frame counter cannot go round half way."""


def two_senders(before_seq: int, before_at: float, after_seq: int, after_at: float) -> str | None:
    """Why two STATUS frames under one id, with no reset between them, cannot come from one
    particle (None if they can): each particle numbers its frames, and its number only grows
    (lost frames leave gaps, never a step back). Two particles switched on together have
    uptimes that agree, but not frame numbers for long."""
    back = (before_seq - after_seq) % 256
    if 0 < back < 128 and after_at - before_at < SEQ_WINDOW_S:
        return f"its frame numbers went back from {before_seq} to {after_seq} with no reset"
    return None


@dataclass
class ParticleRow:
    """Everything heard from one particle, or a particle of the fleet not heard yet."""

    key: str
    """"7"; "7@RADIO" for a second radio answering as 7, and for each particle without an id."""
    id: int
    source: str | None
    first_heard: float
    last_heard: float
    frames: int = 0
    """Frames heard from it; 0 for a fleet particle this session has not heard."""
    status: Status | None = None
    status_time: float | None = None
    intensity: int | None = None
    params: dict[int, tuple[int, int]] = field(default_factory=dict)
    reset_in_run: int | None = None
    """The run during which the particle reset (cleared by the next START)."""
    in_fleet: bool | None = None
    """Whether the fleet file lists its id (None without a fleet)."""
    duplicate: str | None = None
    """Why its id looks like two particles' (None if it does not)."""
    status_seq: int | None = None
    """The frame number of its latest STATUS."""
    told_apart: bool = False
    """A duplicate whose radio tells it from the others (each has a row of its own, and answers
    for itself); on a transparent link two particles with one id cannot be told apart."""

    @property
    def answers_for_itself(self) -> bool:
        """Whether this row's STATUS reports come from one particle only."""
        return self.duplicate is None or self.told_apart

    @property
    def heard(self) -> bool:
        return self.frames > 0

    @property
    def state(self) -> State | None:
        if self.status is None:
            return None
        try:
            return State(self.status.state)
        except ValueError:
            return None

    def silent(self, now: float, after: float = SILENT_AFTER_S) -> bool:
        return now - self.last_heard > after

    def hash_mismatch(self, host_hash: int = DEFINITION_HASH) -> bool:
        return self.status is not None and self.status.definition_hash != host_hash

    @property
    def moving(self) -> bool:
        return self.state in MOVING_STATES

    @property
    def bad_frames(self) -> int | None:
        """Frames that reached the particle damaged, as it reports them."""
        if self.status is None:
            return None
        return self.status.rx_bad_crc + self.status.rx_bad_length

    def flags(
        self, now: float, silent_after: float = SILENT_AFTER_S, host_hash: int = DEFINITION_HASH
    ) -> list[str]:
        """What a person should look at, most urgent first: "DUPLICATE", "SILENT 9s", ..."""
        flags: list[str] = []
        if self.duplicate is not None:
            flags.append("DUPLICATE")
        if self.reset_in_run is not None:
            flags.append(f"RESET in run {self.reset_in_run}")
        if not self.heard:
            flags.append("NOT HEARD")
        elif self.silent(now, silent_after):
            flags.append(f"SILENT {max(0.0, now - self.last_heard):.0f}s")
        if self.in_fleet is False and self.id != UNASSIGNED_ID:
            flags.append("NOT IN FLEET")
        if self.hash_mismatch(host_hash):
            flags.append("HASH MISMATCH")
        if self.id == UNASSIGNED_ID:
            flags.append("NO ID")
        status = self.status
        if status is not None and status.sensor_faults:
            bad = [str(k) for k in range(6) if status.sensor_faults >> k & 1]
            flags.append("SENSOR A" + ",A".join(bad))
        return flags
