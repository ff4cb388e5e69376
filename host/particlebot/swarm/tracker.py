"""What the base station knows of the swarm, and the commands it repeats until confirmed (no UI)."""

from __future__ import annotations

import re
import threading
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Protocol

from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    DEFINITION_HASH,
    UNASSIGNED_ID,
    GetParam,
    Identify,
    Intensity,
    Message,
    Method,
    ParamResult,
    ParamValue,
    Ping,
    ServoHold,
    SetId,
    SetParam,
    Start,
    State,
    Status,
    Stop,
)
from particlebot.radio import LinkEvent, LinkState, Packet, RadioError, ReadOnlyRadioError
from particlebot.resets import ADVICE, reset_between, reset_cause
from particlebot.session import Dropped, Listener, ReceivedFrame, SentFrame
from particlebot.swarm.campaigns import (
    CLOCK_SLACK_S,
    Campaign,
    ParamQuery,
    ids_text,
    param_name,
    result_text,
    state_name,
)
from particlebot.swarm.roster import (
    OBEYED_STOP_STATES,
    RECENT_S,
    RUN_STATES,
    SILENT_AFTER_S,
    STOPPED_STATES,
    ParticleRow,
    two_clocks,
    two_senders,
)

# A particle answers a broadcast SET_PARAM or GET_PARAM in a random one of 10 slots of 60 ms;
# its PARAM_VALUE (15 bytes) then queues behind the others' on the base station's 9600-baud
# link. Two seconds leave room for that and for a radio that repeats a packet.
PARAM_REPLY_TIMEOUT_S = 2.0
PARAM_ATTEMPTS = 10
"""A particle that has not answered a SET or GET is asked again by id, up to nine times."""
PARAM_RETRY_S = 0.5
"""A particle asked by id answers at once (no reply slot): its answer is in within 0.1 s."""
# Particles send STATUS every 2 s: hearing nothing at all for longer than two of those means the
# link, not the swarm, is the likelier problem.
QUIET_HINT_S = 5.0
# The firmware's stop ramp lasts at most 600 ms, so a particle must have STOP within ~0.35 s of
# the command for its servo to be contracted within 1 s. Four copies 0.1 s apart reach a
# particle unless all four are lost: 0.16 % of the time at 20 % loss. Each copy that reaches a
# particle already stopping restarts its ramp from where the body is: up to ~60 ms longer.
STOP_BURST_S = (0.0, 0.1, 0.2, 0.3)
STOP_TIMEOUT_S = 10.0
# A base station that has just started knows nobody: particles it has not heard yet may be
# moving. For this long after it starts, STOP keeps going out (every stop_interval) and asks
# every particle to answer (a broadcast PING every DISCOVERY_PING_S), whatever it has heard, and
# is never called confirmed before it ends. At 50 % loss a particle then stays unheard with a
# chance of about 1 in 500 (five STATUS reports and ten PINGs, each a quarter to a half likely
# to come through); the largest group seen covers most of the rest.
STOP_GRACE_S = 10.0
STOP_AFTER_GRACE_S = 5.0
"""Time left to confirm a STOP given during the grace period, once it is over."""
DISCOVERY_PING_S = 1.0
# PINGs per round: their STATUS replies (52 bytes each) arrive together and queue in the base
# radio's serial buffer, which 9600 baud drains at one reply per ~55 ms.
MAX_PINGS = 4
SERVO_HOLD_TIMEOUT_S = 3.0
"""A SERVO_HOLD sent by id is answered at once with a STATUS; resent every 0.3 s meanwhile."""
RENAME_WINDOW_S = 30.0
"""How long after a SET_ID its new id answering counts as the renamed particle."""
RENAME_SLACK_S = 1.0
"""A STATUS under the old id that arrives this soon after the SET_ID left before it landed."""

_SHARED_SOURCE = re.compile(r"[0-9A-Fa-f]{4}")
"""16-bit XBee addresses: every particle whose radio keeps the factory MY=0 sends from 0000."""


def identifying(source: str | None) -> bool:
    """Whether a packet's source names one radio (a 64-bit address, a simulated node)."""
    return source is not None and not _SHARED_SOURCE.fullmatch(source)


class CommandSink(Protocol):
    """Where the tracker's commands go: a Session, or a fake in tests."""

    def send(self, message: Message) -> object: ...

    def note(self, text: str) -> None: ...


class IdInUseError(ValueError):
    """SET_ID to an id another particle has (in the fleet or heard); force=True overrides."""


@dataclass(frozen=True)
class ModelNote:
    time: float
    text: str
    level: str = "info"  # info, warning, error


@dataclass(frozen=True)
class Rename:
    """A particle that now answers under another id (the owner updates the fleet file)."""

    old_id: int
    new_id: int
    source: str | None


def _fresh(row: ParticleRow, since: float) -> bool:
    """Whether row's last STATUS was received after since (one received at the very moment a
    command went out cannot answer it: the command alone takes milliseconds to arrive)."""
    return row.status_time is not None and row.status_time > since


class SwarmTracker(Listener):
    """Per-particle state from the frames a session delivers, and the commands given to them.

    roster: the particle ids of the fleet file, or None without one. Every roster particle is
    expected to confirm a STOP (shown as NOT HEARD until it answers); without a roster, every
    particle heard in the last recent_s is, and never fewer than the largest group seen.
    """

    def __init__(
        self,
        sink: CommandSink | None,
        clock: Callable[[], float],
        *,
        roster: Iterable[int] | None = None,
        host_hash: int = DEFINITION_HASH,
        silent_after: float = SILENT_AFTER_S,
        recent_s: float = RECENT_S,
        stop_burst: tuple[float, ...] = STOP_BURST_S,
        stop_interval: float = 0.5,
        stop_timeout: float = STOP_TIMEOUT_S,
        stop_grace: float = 0.0,
        start_interval: float = 0.5,
        start_timeout: float = 8.0,
        max_pings: int = MAX_PINGS,
        param_timeout: float = PARAM_REPLY_TIMEOUT_S,
        param_attempts: int = PARAM_ATTEMPTS,
        param_retry: float = PARAM_RETRY_S,
        quiet_hint: str | None = None,
        quiet_after: float | None = None,
    ) -> None:
        """stop_grace: how long after it starts STOP is held open (see STOP_GRACE_S; 0 for a
        tracker that takes over a known swarm, as tests do). quiet_hint: shown once when
        nothing at all has been heard for quiet_after seconds (what to check on this kind of
        radio: its baud, PAN ID and channel)."""
        self.sink = sink
        self.clock = clock
        self.host_hash = host_hash
        self.silent_after = silent_after
        self.recent_s = recent_s
        if not stop_burst or stop_burst[0] != 0.0 or list(stop_burst) != sorted(stop_burst):
            raise ValueError("stop_burst: offsets in seconds, the first 0, in order")
        self.stop_burst = stop_burst
        self.stop_interval = stop_interval
        self.stop_timeout = stop_timeout
        self.start_interval = start_interval
        self.start_timeout = start_timeout
        self.max_pings = max_pings
        self.param_timeout = param_timeout
        self.param_attempts = param_attempts
        self.param_retry = param_retry
        self.quiet_hint = quiet_hint
        self.quiet_after = QUIET_HINT_S if quiet_after is None else quiet_after
        self.opened_at = clock()
        self.grace_until = self.opened_at + stop_grace
        self.queries: list[ParamQuery] = []
        self.run_active = False
        """A START went out and no STOP since."""
        self.particles: dict[str, ParticleRow] = {}
        self.roster: set[int] | None = None if roster is None else set(roster)
        self.largest_group = 0
        """The most particles known to exist at once: together in an estimation round (the
        group size their STATUS reports) or heard together."""
        self.forgotten = 0
        """Particles removed by hand (forget): each lowers what the largest group asks for."""
        self.notes: deque[ModelNote] = deque(maxlen=500)
        self.notes_written = 0
        self.drops: dict[str, int] = {}
        self.packets = 0
        self.frames = 0
        self.sent = 0
        self.link: LinkEvent | None = None
        self.run_id = 0
        self.campaigns: list[Campaign] = []
        self.renames: list[Rename] = []
        """Renames seen and not yet taken by the owner (take_renames)."""
        self._set_ids: dict[int, tuple[int, float]] = {}
        """new id -> (old id, when SET_ID went out)"""
        self._lock = threading.RLock()
        for particle_id in sorted(self.roster or ()):
            self._add_row(str(particle_id), particle_id, None, self.opened_at, heard=False)

    # ---- what the session delivers ---------------------------------------------------------

    def on_packet(self, packet: Packet) -> None:
        with self._lock:
            self.packets += 1

    def on_frame(self, received: ReceivedFrame) -> None:
        frame = received.frame
        if frame.sender == BASE_STATION_ID:
            return  # another base station, or our own frame echoed
        source = None if received.source is None else str(received.source)
        with self._lock:
            self.frames += 1
            row = self._row_for(frame.sender, source, received.time)
            if not row.heard:  # a fleet particle heard for the first time
                row.first_heard = received.time
            row.last_heard = max(row.last_heard, received.time)
            row.frames += 1
            message = frame.message
            if isinstance(message, Status):
                self._on_status(row, message, received.time, frame.seq)
            elif isinstance(message, Intensity):
                row.intensity = message.intensity
            elif isinstance(message, ParamValue):
                row.params[message.param] = (message.result, message.value)
                self._on_param_value(row, message, received.time)
            self._count_heard(received.time)
        # Campaigns advance in poll(), on the caller's thread: commands never go out from the
        # receive thread, which must keep reading the radio.

    def _add_row(
        self, key: str, particle_id: int, source: str | None, at: float, *, heard: bool = True
    ) -> ParticleRow:
        row = ParticleRow(key, particle_id, source, at, at)
        if self.roster is not None:
            row.in_fleet = particle_id in self.roster
        self.particles[key] = row
        if not heard:
            return row
        if particle_id == UNASSIGNED_ID:
            self._note(
                f"A particle without an id answered (id {UNASSIGNED_ID}); give it one "
                f"with: setid {UNASSIGNED_ID} NEW_ID",
                "warning",
            )
        elif row.in_fleet is False:
            self._note(
                f"Particle {particle_id} is not in the fleet file: a particle of another "
                "fleet, or one flashed without it (particlebot flash --id records one)",
                "warning",
            )
        return row

    def _row_for(self, sender: int, source: str | None, at: float) -> ParticleRow:
        """The row a frame belongs to, made if needed; renames and duplicates are seen here."""
        if sender == UNASSIGNED_ID:
            # Unassigned particles all share one id; keep them apart by radio address.
            key = str(sender) if source is None else f"{sender}@{source}"
            row = self.particles.get(key)
            return row if row is not None else self._add_row(key, sender, source, at)
        if identifying(source):
            self._drop_renamed(sender, source, at)
        same_id = [row for row in self.particles.values() if row.id == sender]
        if sender in self._set_ids:
            self._drop_set_id_origin(sender, at)
        for row in same_id:
            if not identifying(source) or not identifying(row.source) or row.source == source:
                if row.source is None:
                    row.source = source
                return row
        key = str(sender) if not same_id else f"{sender}@{source}"
        row = self._add_row(key, sender, source, at)
        if same_id:
            radios = " and ".join(str(other.source) for other in [*same_id, row])
            why = f"radios {radios} both answer as particle {sender}"
            for other in [*same_id, row]:
                other.duplicate = why
                other.told_apart = True
            self._note_duplicate(sender, why)
        return row

    def _note_duplicate(self, particle_id: int, why: str) -> None:
        self._note(
            f"DUPLICATE id {particle_id}: {why}. Switch all but one off, then give it another "
            f"id (setid {particle_id} NEW_ID), switch the next one on, and so on",
            "error",
        )

    def _drop_renamed(self, sender: int, source: str | None, at: float) -> None:
        """A radio that answered as another id before now answers as sender: the particle was
        renamed (by this console, or by `flash` or another console): its old row goes."""
        for row in list(self.particles.values()):
            if row.source == source and row.id != sender:
                self._drop_row(row, sender, at)

    def _drop_set_id_origin(self, new_id: int, at: float) -> None:
        """The new id of a SET_ID sent from here answers (a transparent link shows no radio):
        the old id's row goes, unless it was heard after the SET_ID went out."""
        old_id, sent_at = self._set_ids.pop(new_id)
        if at - sent_at > RENAME_WINDOW_S:
            return
        for row in list(self.particles.values()):
            if row.id == old_id and row.last_heard <= sent_at + RENAME_SLACK_S:
                self._drop_row(row, new_id, at)

    def _drop_row(self, row: ParticleRow, new_id: int, at: float) -> None:
        del self.particles[row.key]
        if row.id != UNASSIGNED_ID:
            self.renames.append(Rename(row.id, new_id, row.source))
        if self.roster is not None and row.id in self.roster:
            # The same particle under its new id: the fleet's record follows it.
            self.roster.discard(row.id)
            self.roster.add(new_id)
            for other in self.particles.values():
                if other.id == new_id:
                    other.in_fleet = True
        self._note(
            f"Particle {row.id} now answers as {new_id}"
            + (f" (radio {row.source})" if row.source else "")
            + f": row {row.id} dropped"
        )
        for campaign in self.campaigns:
            campaign.pending.discard(row.key)
            campaign.confirmed.discard(row.key)
        self._recheck_duplicates(row.id)

    def _recheck_duplicates(self, particle_id: int) -> None:
        """Clears the duplicate flag of an id left with one radio (the other was renamed)."""
        same = [row for row in self.particles.values() if row.id == particle_id]
        if len(same) == 1 and same[0].told_apart:
            same[0].duplicate = None
            same[0].told_apart = False

    def _count_heard(self, now: float) -> None:
        together = sum(
            1
            for row in self.particles.values()
            if row.heard and not row.silent(now, self.silent_after)
        )
        self.largest_group = max(self.largest_group, together)

    def _on_status(self, row: ParticleRow, status: Status, at: float, seq: int) -> None:
        first_mismatch = status.definition_hash != self.host_hash and (
            row.status is None or row.status.definition_hash == self.host_hash
        )
        previous = row.status
        # Particles without an id all answer as 254: nothing to tell apart there.
        if previous is not None and row.status_time is not None and row.id != UNASSIGNED_ID:
            why = two_clocks(previous, row.status_time, status, at)
            if why is None and row.status_seq is not None and not reset_between(previous, status):
                why = two_senders(row.status_seq, row.status_time, seq, at)
            if why is not None and not row.duplicate:
                row.duplicate = f"two particles answer as {row.id}: {why}"
                row.told_apart = False
                self._note_duplicate(row.id, row.duplicate)
            elif why is None and reset_between(previous, status):
                self._on_reset(row, previous, status)
        row.status = status
        row.status_time = at
        row.status_seq = seq
        row.intensity = status.intensity
        if status.state in RUN_STATES:
            self.largest_group = max(self.largest_group, status.group_size)
        if first_mismatch:
            self._note(
                f"Particle {row.id} runs firmware built from protocol "
                f"0x{status.definition_hash:08X}, this host from 0x{self.host_hash:08X}: reflash "
                "it (or update the host) before trusting its fields.",
                "warning",
            )

    def _on_reset(self, row: ParticleRow, before: Status, after: Status) -> None:
        cause = reset_cause(after.last_reset_cause)
        why = f"{cause}: {ADVICE[cause]}" if cause in ADVICE else cause
        if before.state in RUN_STATES or self.run_active:
            run = before.run_id if before.state in RUN_STATES else self.run_id
            row.reset_in_run = run
            self._note(
                f"Particle {row.id} reset during run {run} ({why}); it is "
                f"{state_name(after.state)} now, out of the run",
                "error",
            )
        else:
            self._note(f"Particle {row.id} reset ({why})", "warning")

    def _on_param_value(self, row: ParticleRow, message: ParamValue, at: float) -> None:
        for query in reversed(self.queries):
            if query.accepts(row.id, message.param):
                query.replies[row.id] = (message.result, message.value)
                # With no particle known when it went out, only the timeout ends a broadcast.
                everyone = bool(query.expected) and query.expected <= set(query.replies)
                if query.target != BROADCAST_ID or everyone:
                    self._conclude_query(query, at)
                return
        # Nobody here asked (another console, a late answer): one line of its own.
        self._note(_param_text(row.id, message))

    def _conclude_query(self, query: ParamQuery, now: float) -> None:
        query.done = True
        query.finished_at = now
        if query.target != BROADCAST_ID and query.replies:
            result, value = query.replies[query.target]
            name = param_name(query.param)
            if query.kind == "SET" and result != ParamResult.OK:
                text = (
                    f"Particle {query.target}: SET {name} = {query.value} refused, "
                    f"{result_text(result)}; it stays {value}"
                )
            else:
                text = f"Particle {query.target}: {name} = {value} ({result_text(result)})"
            self._note(text, "info" if result == ParamResult.OK else "warning")
            return
        everyone_ok = query.replies and all(
            result == ParamResult.OK for result, _ in query.replies.values()
        )
        complete = query.expected <= set(query.replies)
        level = "info" if everyone_ok and complete else "warning"
        self._note(query.summary(round(now - query.started, 1)), level)

    def on_dropped(self, dropped: Dropped) -> None:
        with self._lock:
            reason = dropped.event.reason.value
            self.drops[reason] = self.drops.get(reason, 0) + 1

    def on_sent(self, sent: SentFrame) -> None:
        with self._lock:
            self.sent += 1

    def on_link(self, event: LinkEvent) -> None:
        with self._lock:
            self.link = event
            level = "info" if event.state is LinkState.CONNECTED else "warning"
            if event.state is LinkState.CLOSED:
                level = "error" if "closed" not in event.message else "info"
            self._note(event.message, level, log=False)

    # ---- views -----------------------------------------------------------------------------

    def rows(self) -> list[ParticleRow]:
        with self._lock:
            return sorted(self.particles.values(), key=lambda row: (row.id, row.key))

    def heard_rows(self, now: float | None = None) -> list[ParticleRow]:
        """Particles that have reported a STATUS and are not silent."""
        at = self.clock() if now is None else now
        with self._lock:
            return [
                row
                for row in self.rows()
                if row.status is not None and not row.silent(at, self.silent_after)
            ]

    def moving_ids(self) -> list[int]:
        """Ids of the particles whose latest STATUS shows them in a run (estimating, waiting,
        cycling or pausing), silent ones included: nothing says they stopped."""
        with self._lock:
            return sorted({row.id for row in self.particles.values() if row.moving})

    def ids_in_use(self) -> set[int]:
        """Ids the fleet lists or a particle answered with lately."""
        now = self.clock()
        with self._lock:
            heard = {
                row.id
                for row in self.particles.values()
                if row.heard and now - row.last_heard <= self.recent_s
            }
            return heard | (self.roster or set())

    def new_notes(self) -> list[ModelNote]:
        """Notes added since the previous call (for a UI that appends them to a log pane)."""
        with self._lock:
            fresh = self.notes_written
            total = len(self.notes)
            count = min(fresh, total)
            self.notes_written = 0
            return list(self.notes)[total - count :]

    def take_renames(self) -> list[Rename]:
        with self._lock:
            renames, self.renames = self.renames, []
            return renames

    def last(self, name: str) -> Campaign | None:
        with self._lock:
            for campaign in reversed(self.campaigns):
                if campaign.name == name:
                    return campaign
        return None

    def counters_text(self) -> str:
        with self._lock:
            drops = self.drops
            bad = drops.get("bad_crc", 0) + drops.get("bad_length", 0) + drops.get("truncated", 0)
            return (
                f"frames {self.frames}  bad {bad} (crc {drops.get('bad_crc', 0)}, "
                f"len {drops.get('bad_length', 0)}, cut {drops.get('truncated', 0)})  "
                f"noise {drops.get('skipped', 0)}B  unknown "
                f"{drops.get('unknown_type', 0) + drops.get('bad_payload', 0)}  sent {self.sent}"
            )

    def required_count(self) -> int:
        """How many particles a STOP needs confirmed at least: the largest group seen, less the
        particles forgotten by hand."""
        with self._lock:
            return max(0, self.largest_group - self.forgotten)

    def unconfirmed(self, campaign: Campaign) -> list[tuple[int, str]]:
        """(particle id, why it has not confirmed) for each particle the campaign waits for."""
        with self._lock:
            reasons: list[tuple[int, str]] = []
            for key in sorted(campaign.pending, key=lambda k: (self._id_of(k), k)):
                row = self.particles.get(key)
                if row is None:
                    continue
                reasons.append((row.id, self._why_pending(campaign, row)))
            return reasons

    def _id_of(self, key: str) -> int:
        row = self.particles.get(key)
        return 256 if row is None else row.id

    def _why_pending(self, campaign: Campaign, row: ParticleRow) -> str:
        if not row.answers_for_itself:
            return f"duplicate id: {row.duplicate}; their answers cannot be told apart"
        if not row.heard:
            return "in the fleet, never heard in this session"
        if not _fresh(row, campaign.started):
            ago = campaign.started - row.last_heard
            when = f"{ago:.0f} s before the command" if ago >= 0 else "only since"
            return f"no STATUS since the command (last heard {when})"
        if campaign.name == "START" and row.status is not None:
            return f"reports run {row.status.run_id}, not run {self.run_id}"
        return f"reports {state_name(row.status.state) if row.status else '?'}"

    # ---- commands --------------------------------------------------------------------------

    def start(
        self,
        method: Method,
        *,
        cycle_steps: int = 0,
        wave_size: int = 0,
        update_interval_s: int = 0,
        phototaxis: bool = False,
    ) -> Campaign:
        with self._lock:
            self._cancel("STOP")
            self._cancel("START")
            self.run_active = True
            for row in self.particles.values():
                row.reset_in_run = None
            reported = [row.status.run_id for row in self.particles.values() if row.status]
            self.run_id = (max([self.run_id, *reported]) % 255) + 1
            message = Start(
                run_id=self.run_id,
                method=int(method),
                cycle_steps=cycle_steps,
                wave_size=wave_size,
                update_interval_s=update_interval_s,
                phototaxis=int(phototaxis),
            )
            run_id = self.run_id

            def confirms(key: str, since: float) -> bool:
                row = self.particles.get(key)
                return (
                    row is not None
                    and row.answers_for_itself
                    and _fresh(row, since)
                    and row.status is not None
                    and row.status.run_id == run_id
                )

            def needs_command(key: str, since: float) -> bool:
                # It answered but is in another run: it missed START. The copy carries the same
                # run_id, so particles already in the run ignore it.
                row = self.particles.get(key)
                return (
                    row is not None
                    and _fresh(row, since)
                    and row.status is not None
                    and row.status.run_id != run_id
                )

            now = self.clock()
            return self._launch(
                Campaign(
                    name="START",
                    command=message,
                    started=now,
                    burst=(0.0,),
                    interval=self.start_interval,
                    deadline=now + self.start_timeout,
                    pending=self._present_keys(now),
                    confirms=confirms,
                    needs_command=needs_command,
                )
            )

    def stop(self) -> Campaign:
        """STOP as a burst (stop_burst), then PINGs until every expected particle reports IDLE
        or DONE, or stop_timeout passes. STOP is repeated after the burst only while some
        particle has not answered STOPPING, IDLE or DONE since (a copy restarts the stop ramp
        of a particle that has it already), and throughout the grace period after the base
        station started."""
        with self._lock:
            self._cancel("START")
            self._cancel("STOP")
            self.run_active = False

            def confirms(key: str, since: float) -> bool:
                row = self.particles.get(key)
                return (
                    row is not None
                    and row.answers_for_itself
                    and _fresh(row, since)
                    and row.state in STOPPED_STATES
                )

            def needs_command(key: str, since: float) -> bool:
                row = self.particles.get(key)
                return row is None or not (_fresh(row, since) and row.state in OBEYED_STOP_STATES)

            now = self.clock()
            deadline = now + self.stop_timeout
            if self.grace_until > now:
                deadline = max(deadline, self.grace_until + STOP_AFTER_GRACE_S)
            return self._launch(
                Campaign(
                    name="STOP",
                    command=Stop(),
                    started=now,
                    burst=self.stop_burst,
                    interval=self.stop_interval,
                    deadline=deadline,
                    pending=self._expected_keys(now),
                    confirms=confirms,
                    needs_command=needs_command,
                    required=self.required_count,
                    hold_until=self.grace_until,
                )
            )

    def servo_hold(self, target: int, pulse_us: int, hold_s: int) -> Campaign:
        """SERVO_HOLD to one particle until its STATUS shows it holding pulse_us (hold_s > 0)
        or no longer holding (hold_s = 0), or SERVO_HOLD_TIMEOUT_S pass. A particle that is
        running answers with its unchanged state: the campaign fails, saying which."""
        with self._lock:
            self._cancel("SERVO_HOLD")

            def confirms(key: str, since: float) -> bool:
                row = self.particles.get(key)
                if row is None or not _fresh(row, since) or row.status is None:
                    return False
                holding = row.status.state == State.HOLDING
                if hold_s == 0:
                    return not holding
                return holding and row.status.servo_pulse_us == pulse_us

            def needs_command(key: str, since: float) -> bool:
                return not confirms(key, since)

            now = self.clock()
            return self._launch(
                Campaign(
                    name="SERVO_HOLD",
                    command=ServoHold(target=target, pulse_us=pulse_us, hold_s=hold_s),
                    started=now,
                    burst=(0.0,),
                    interval=0.3,
                    deadline=now + SERVO_HOLD_TIMEOUT_S,
                    pending={
                        row.key for row in self.particles.values() if row.id == target and row.heard
                    },
                    confirms=confirms,
                    needs_command=needs_command,
                    join_new=False,
                )
            )

    def _present_keys(self, now: float) -> set[str]:
        """Particles that answer now: START waits for these."""
        return {
            row.key
            for row in self.particles.values()
            if row.heard and not row.silent(now, self.silent_after)
        }

    def _expected_keys(self, now: float) -> set[str]:
        """Particles that must confirm a STOP: the fleet's and those heard lately."""
        return {
            row.key
            for row in self.particles.values()
            if (not row.heard and self.roster is not None and row.id in self.roster)
            or (row.heard and now - row.last_heard <= self.recent_s)
        }

    def set_param(
        self, param: int, value: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends SET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        message = SetParam(target=target, param=param, value=value)
        return self._query("SET", message, value, attempts)

    def get_param(
        self, param: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends GET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        return self._query("GET", GetParam(target=target, param=param), None, attempts)

    def _query(
        self, kind: str, message: SetParam | GetParam, value: int | None, attempts: int | None
    ) -> ParamQuery:
        with self._lock:
            now = self.clock()
            if message.target == BROADCAST_ID:
                expected = {row.id for row in self.heard_rows(now) if row.id != UNASSIGNED_ID}
            else:
                expected = {message.target}
            query = ParamQuery(
                kind,
                message.param,
                value,
                message.target,
                now,
                expected,
                attempts=self.param_attempts if attempts is None else attempts,
                first_wait=self.param_timeout,
                retry_after=self.param_retry,
                last_asked=now,
            )
            if self._send(message):
                self.queries = [*(q for q in self.queries if not q.done), query]
            else:
                query.done = True
                query.finished_at = now
            return query

    def identify(self, target: int = BROADCAST_ID) -> None:
        self._send_once(Identify(target=target))

    def set_id(self, target: int, new_id: int, *, force: bool = False) -> None:
        """Sends SET_ID; IdInUseError if new_id is the fleet's or a particle's heard lately
        (force: the other one is gone, or is being renamed too)."""
        with self._lock:
            if not force and new_id in self.ids_in_use() and new_id != target:
                where = "the fleet lists it" if new_id in (self.roster or ()) else "it answers"
                raise IdInUseError(
                    f"id {new_id} is in use ({where}); two particles with one id cannot be told "
                    f"apart. Choose a free id, or force it (setid {target} {new_id} force) if "
                    f"particle {new_id} is gone"
                )
            if force and new_id != target and self._remove_rows(new_id):
                self._note(f"Particle {new_id}'s row dropped: SET_ID gives its id to another")
            if self._send(SetId(target=target, new_id=new_id)):
                self._set_ids[new_id] = (target, self.clock())

    def forget(self, particle_id: int) -> int:
        """Removes every row of this id (and takes it off this session's roster): a particle
        that is gone for good. Returns how many rows went; one heard again comes back."""
        with self._lock:
            removed = self._remove_rows(particle_id)
            if self.roster is not None:
                self.roster.discard(particle_id)
            if removed:
                self._note(
                    f"Particle {particle_id} forgotten: no longer expected (it comes back if "
                    "it is heard again)"
                )
            return removed

    def _remove_rows(self, particle_id: int) -> int:
        keys = [row.key for row in self.particles.values() if row.id == particle_id]
        for key in keys:
            del self.particles[key]
            for campaign in self.campaigns:
                campaign.pending.discard(key)
                campaign.confirmed.discard(key)
        if keys:
            self.forgotten += 1
        return len(keys)

    def ping(self, target: int = BROADCAST_ID) -> None:
        self._send_once(Ping(target=target))

    def note(self, text: str, level: str = "info") -> None:
        """Shows text to the person (and writes it to the log)."""
        with self._lock:
            self._note(text, level)

    def poll(self, now: float | None = None) -> None:
        """Advances campaigns: confirmations, resends, timeouts. Call a few times a second."""
        at = self.clock() if now is None else now
        with self._lock:
            for campaign in self.campaigns:
                if not campaign.done:
                    self._advance(campaign, at)
            for query in self.queries:
                if not query.done and at >= query.next_ask - CLOCK_SLACK_S:
                    self._retry_query(query, at)
            quiet = self.packets == 0 and at - self.opened_at >= self.quiet_after
            if self.quiet_hint is not None and quiet:
                hint = f"Nothing heard for {self.quiet_after:g} s. {self.quiet_hint}"
                self._note(hint, "warning")
                self.quiet_hint = None

    # ---- internals -------------------------------------------------------------------------

    def _retry_query(self, query: ParamQuery, now: float) -> None:
        """Asks each particle that has not answered again, by id; concludes after the last try."""
        missing = query.missing
        if query.asked >= query.attempts or not missing:
            self._conclude_query(query, now)
            return
        query.asked += 1
        query.last_asked = now
        for particle in missing:
            if query.kind == "SET" and query.value is not None:
                message: Message = SetParam(target=particle, param=query.param, value=query.value)
            else:
                message = GetParam(target=particle, param=query.param)
            if not self._send(message):
                self._conclude_query(query, now)
                return

    def _launch(self, campaign: Campaign) -> Campaign:
        campaign.next_send = campaign.started
        self.campaigns = [*self.campaigns[-7:], campaign]
        self._advance(campaign, campaign.started)
        return campaign

    def _cancel(self, name: str) -> None:
        for campaign in self.campaigns:
            if campaign.name == name and not campaign.done:
                campaign.done = True
                campaign.outcome = f"{name} superseded"

    def _advance(self, campaign: Campaign, now: float) -> None:
        if campaign.join_new:
            for row in self.particles.values():
                new = row.heard and row.first_heard > campaign.started
                if new and row.key not in campaign.confirmed:
                    campaign.pending.add(row.key)
        # Judged on each particle's latest STATUS: one that confirmed can fall back (a late
        # copy of STOP finds it stopped and it reports STOPPING again, for a moment).
        for key in campaign.pending | campaign.confirmed:
            if key not in self.particles:
                campaign.pending.discard(key)
                campaign.confirmed.discard(key)
            elif campaign.confirms(key, campaign.started):
                campaign.pending.discard(key)
                campaign.confirmed.add(key)
            else:
                campaign.confirmed.discard(key)
                campaign.pending.add(key)
        # The whole burst goes out even when every known particle has confirmed: particles the
        # base station has not heard of yet have no other chance of getting the command.
        settled = (
            campaign.burst_sent
            and not campaign.pending
            and now >= campaign.hold_until - CLOCK_SLACK_S
            and len(campaign.confirmed) >= campaign.required()
        )
        if now >= campaign.deadline - CLOCK_SLACK_S or settled:
            self._conclude(campaign, now)
        elif now >= campaign.next_send - CLOCK_SLACK_S:
            self._send_round(campaign, now)

    def _conclude(self, campaign: Campaign, now: float) -> None:
        elapsed = now - campaign.started
        required = campaign.required()
        confirmed = len(campaign.confirmed)
        if campaign.pending:
            missing = [self.particles[key] for key in campaign.pending]
            shortfall = ""
            if required > confirmed + len(missing):
                shortfall = (
                    f"; {required} were seen together, so "
                    f"{required - confirmed - len(missing)} more never answered"
                )
            self._finish(
                campaign,
                now,
                False,
                f"{campaign.name} not confirmed within {campaign.timeout:.0f} s by "
                f"particle(s) {ids_text([row.id for row in missing])} ({confirmed} confirmed"
                f"{shortfall}); check they are switched on and in range, then try again",
            )
        elif confirmed < required:
            self._finish(
                campaign,
                now,
                False,
                f"{campaign.name} not confirmed within {campaign.timeout:.0f} s: {confirmed} "
                f"particle(s) confirmed, but {required} were seen together; "
                f"{required - confirmed} never answered (forget ID drops one that is gone)",
            )
        elif campaign.confirmed:
            self._finish(
                campaign,
                now,
                True,
                f"{campaign.name} confirmed by all {confirmed} particles in {elapsed:.1f} s",
            )
        else:
            self._finish(
                campaign, now, True, f"{campaign.name} sent; no particles known to confirm it"
            )

    def _send_round(self, campaign: Campaign, now: float) -> None:
        index = campaign.rounds
        campaign.rounds += 1
        if campaign.rounds < len(campaign.burst):
            # Offsets from the start, not from this round: a late poll does not delay the rest.
            campaign.next_send = campaign.started + campaign.burst[campaign.rounds]
        else:
            campaign.next_send = now + campaign.interval
        in_burst = index < len(campaign.burst)
        holding = now < campaign.hold_until
        wanted = (
            in_burst
            or holding
            or any(campaign.needs_command(key, campaign.started) for key in campaign.pending)
        )
        if wanted and not self._send(campaign.command, campaign):
            return
        if campaign.burst_sent:
            if holding and now - campaign.last_broadcast_ping >= DISCOVERY_PING_S - CLOCK_SLACK_S:
                campaign.last_broadcast_ping = now
                if not self._send(Ping(target=BROADCAST_ID), campaign):
                    return
            for target in self._ping_targets(campaign):
                if not self._send(Ping(target=target), campaign):
                    return

    def _ping_targets(self, campaign: Campaign) -> list[int]:
        """Ids to PING this round: the pending particles pinged least so far, at most
        max_pings. Unassigned particles share id 254, so one PING asks all of them."""
        order = sorted(
            campaign.pending,
            key=lambda key: (campaign.pings.get(key, 0), self.particles[key].id, key),
        )
        targets: list[int] = []
        for key in order:
            particle_id = self.particles[key].id
            if particle_id not in targets:
                if len(targets) >= self.max_pings:
                    continue
                targets.append(particle_id)
            campaign.pings[key] = campaign.pings.get(key, 0) + 1
        return targets

    def _finish(
        self, campaign: Campaign, now: float, success: bool, text: str, *, log: bool = True
    ) -> None:
        campaign.done = True
        campaign.success = success
        campaign.outcome = text
        campaign.finished_at = now
        if log:
            self._note(text, "info" if success else "error")

    def _send_once(self, message: Message) -> None:
        with self._lock:
            self._send(message)

    def _send(self, message: Message, campaign: Campaign | None = None) -> bool:
        """Sends message; a failure is noted once per campaign (not once per resend), and ends
        the campaign when the radio can never send (a replay)."""
        if self.sink is None:
            error: RadioError = ReadOnlyRadioError("Nothing can be sent: no radio")
        else:
            try:
                self.sink.send(message)
                return True
            except RadioError as exc:
                error = exc
        name = type(message).__name__.upper()
        if campaign is None or not campaign.send_failures:
            self._note(f"Could not send {name}: {error}", "error", log=False)
        if campaign is not None:
            campaign.send_failures += 1
            if isinstance(error, ReadOnlyRadioError):
                self._finish(campaign, self.clock(), False, f"{campaign.name} not sent", log=False)
        return False

    def _note(self, text: str, level: str = "info", *, log: bool = True) -> None:
        self.notes.append(ModelNote(self.clock(), text, level))
        self.notes_written += 1
        if log and self.sink is not None:
            self.sink.note(text)


def _param_text(particle: int, message: ParamValue) -> str:
    result = result_text(message.result)
    return f"Particle {particle}: {param_name(message.param)} = {message.value} ({result})"
