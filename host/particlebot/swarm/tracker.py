"""What the console knows about the swarm, and the commands it sends: no UI, so it is testable."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
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
    Param,
    ParamResult,
    ParamValue,
    Ping,
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

# STATUS comes every STATUS_PERIOD_MS (2 s by default, +-25 %): three missed ones mean trouble.
SILENT_AFTER_S = 6.5
STOPPED_STATES = frozenset({State.IDLE, State.DONE})
OBEYED_STOP_STATES = frozenset({State.STOPPING, State.IDLE, State.DONE})
MOVING_STATES = frozenset({State.ESTIMATING, State.WAITING, State.CYCLING, State.PAUSED})
"""A particle in one of these is in a run: quitting or restarting would leave it, or cut it."""
RUN_STATES = MOVING_STATES | {State.STOPPING}
# A particle answers a broadcast SET_PARAM or GET_PARAM in a random one of 10 slots of 60 ms;
# its PARAM_VALUE (15 bytes) then queues behind the others' on the base station's 9600-baud
# link. Two seconds leave room for that and for a radio that repeats a packet.
PARAM_REPLY_TIMEOUT_S = 2.0
# Particles send STATUS every 2 s: hearing nothing at all for longer than two of those means the
# link, not the swarm, is the likelier problem.
QUIET_HINT_S = 5.0
# The firmware's stop ramp lasts at most 600 ms, so a particle must have STOP within ~0.35 s of
# the command for its servo to be contracted within 1 s. Four copies 0.1 s apart reach a
# particle unless all four are lost: 0.16 % of the time at 20 % loss. Each copy that reaches a
# particle already stopping restarts its ramp from where the body is: up to ~60 ms longer.
STOP_BURST_S = (0.0, 0.1, 0.2, 0.3)
# PINGs per round: their STATUS replies (52 bytes each) arrive together and queue in the base
# radio's serial buffer, which 9600 baud drains at one reply per ~55 ms.
MAX_PINGS = 4
# Clock readings are ~1.7e9 s since the epoch, where a float's rounding is ~2e-7 s: a poll at
# exactly the time a copy is due must not miss it by a rounding error.
CLOCK_SLACK_S = 1e-6


class CommandSink(Protocol):
    """Where the model's commands go: a Session, or a fake in tests."""

    def send(self, message: Message) -> object: ...

    def note(self, text: str) -> None: ...


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


@dataclass
class ParticleRow:
    """Everything heard from one particle."""

    key: str
    id: int
    source: str | None
    first_heard: float
    last_heard: float
    frames: int = 0
    status: Status | None = None
    status_time: float | None = None
    intensity: int | None = None
    params: dict[int, tuple[int, int]] = field(default_factory=dict)
    reset_in_run: int | None = None
    """The run during which the particle reset (cleared by the next START)."""

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


@dataclass
class Campaign:
    """A command broadcast until every targeted particle confirms it, or time runs out.

    802.15.4 broadcasts are not acknowledged, so the only proof a particle obeyed is a STATUS it
    sent afterwards. The command goes out once at each offset in `burst` (seconds after
    `started`). With the last of those copies, and then every `interval`, a round PINGs the
    particles still pending by id, a few at a time, so that their STATUS comes at once rather
    than with the next periodic one; a round after the burst repeats the command only if some
    pending particle `needs_command` (a particle's answer shows it missed it, or none came).
    """

    name: str
    command: Message
    started: float
    burst: tuple[float, ...]
    interval: float
    timeout: float
    pending: set[str]
    confirms: Callable[[ParticleRow, float], bool]
    needs_command: Callable[[ParticleRow, float], bool]
    confirmed: set[str] = field(default_factory=set)
    rounds: int = 0
    pings: dict[str, int] = field(default_factory=dict)
    """PINGs sent to each particle (by key)."""
    next_send: float = 0.0
    send_failures: int = 0
    done: bool = False
    success: bool = False
    outcome: str = ""
    finished_at: float | None = None

    @property
    def burst_sent(self) -> bool:
        return self.rounds >= len(self.burst)


@dataclass
class ParamQuery:
    """A SET_PARAM or GET_PARAM waiting for its PARAM_VALUE answers. Answers to a broadcast are
    summarised in one note once every particle known when it went out answered, or at its timeout,
    rather than shown one line per particle."""

    kind: str  # "SET" or "GET"
    param: int
    value: int | None
    target: int
    started: float
    expected: set[int]
    replies: dict[int, tuple[int, int]] = field(default_factory=dict)
    """particle id -> (ParamResult, value)"""
    done: bool = False

    def accepts(self, sender: int, param: int) -> bool:
        return (
            not self.done
            and param == self.param
            and (self.target == BROADCAST_ID or self.target == sender)
        )

    def summary(self, timeout: float) -> str:
        """e.g. "SET CYCLE_STEPS = 300: 8/10 OK; BUSY: 3, 7 (STOP them first)"."""
        name = param_name(self.param)
        head = f"{self.kind} {name}" + (f" = {self.value}" if self.kind == "SET" else "")
        if self.target != BROADCAST_ID:
            head = f"{head} to particle {self.target}"
        missing = sorted(self.expected - set(self.replies))
        if not self.replies:
            if self.target != BROADCAST_ID:
                return f"{head}: no answer within {timeout:g} s"
            return f"{head}: no particle answered within {timeout:g} s"
        parts: list[str] = []
        if self.kind == "SET":
            ok = [i for i, (result, _) in self.replies.items() if result == ParamResult.OK]
            parts.append(f"{len(ok)}/{len(self.expected | set(self.replies))} OK")
            for result in sorted({r for r, _ in self.replies.values()} - {ParamResult.OK}):
                ids = [i for i, (r, _) in self.replies.items() if r == result]
                advice = " (STOP them first)" if result == ParamResult.BUSY else ""
                parts.append(f"{result_name(result)}: {ids_text(ids)}{advice}")
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


@dataclass(frozen=True)
class ModelNote:
    time: float
    text: str
    level: str = "info"  # info, warning, error


def _fresh(row: ParticleRow, since: float) -> bool:
    """Whether row's last STATUS was received after since (one received at the very moment a
    command went out cannot answer it: the command alone takes milliseconds to arrive)."""
    return row.status_time is not None and row.status_time > since


def _ids_text(rows: list[ParticleRow]) -> str:
    return ", ".join(str(row.id) for row in sorted(rows, key=lambda r: r.id))


def ids_text(ids: list[int] | set[int]) -> str:
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


class ConsoleModel(Listener):
    """Per-particle state from the frames a session delivers, and the commands a person gives."""

    def __init__(
        self,
        sink: CommandSink | None,
        clock: Callable[[], float],
        *,
        host_hash: int = DEFINITION_HASH,
        silent_after: float = SILENT_AFTER_S,
        stop_burst: tuple[float, ...] = STOP_BURST_S,
        stop_interval: float = 0.5,
        stop_timeout: float = 10.0,
        start_interval: float = 0.5,
        start_timeout: float = 8.0,
        max_pings: int = MAX_PINGS,
        param_timeout: float = PARAM_REPLY_TIMEOUT_S,
        quiet_hint: str | None = None,
        quiet_after: float | None = None,
    ) -> None:
        """quiet_hint: shown once when nothing at all has been heard for quiet_after seconds (what
        to check on this kind of radio: its baud, PAN ID and channel)."""
        self.sink = sink
        self.clock = clock
        self.host_hash = host_hash
        self.silent_after = silent_after
        if not stop_burst or stop_burst[0] != 0.0 or list(stop_burst) != sorted(stop_burst):
            raise ValueError("stop_burst: offsets in seconds, the first 0, in order")
        self.stop_burst = stop_burst
        self.stop_interval = stop_interval
        self.stop_timeout = stop_timeout
        self.start_interval = start_interval
        self.start_timeout = start_timeout
        self.max_pings = max_pings
        self.param_timeout = param_timeout
        self.quiet_hint = quiet_hint
        self.quiet_after = QUIET_HINT_S if quiet_after is None else quiet_after
        self.opened_at = clock()
        self.queries: list[ParamQuery] = []
        self.run_active = False
        """A START went out and no STOP since."""
        self.particles: dict[str, ParticleRow] = {}
        self.notes: deque[ModelNote] = deque(maxlen=500)
        self.notes_written = 0
        self.drops: dict[str, int] = {}
        self.packets = 0
        self.frames = 0
        self.sent = 0
        self.link: LinkEvent | None = None
        self.run_id = 0
        self.campaigns: list[Campaign] = []
        self._lock = threading.RLock()

    # ---- what the session delivers ---------------------------------------------------------

    def on_packet(self, packet: Packet) -> None:
        with self._lock:
            self.packets += 1

    def on_frame(self, received: ReceivedFrame) -> None:
        frame = received.frame
        if frame.sender == BASE_STATION_ID:
            return  # another base station, or our own frame echoed
        source = None if received.source is None else str(received.source)
        # Unassigned particles all share one id; keep them apart by radio address where known.
        key = str(frame.sender)
        if frame.sender == UNASSIGNED_ID and source is not None:
            key = f"{frame.sender}@{source}"
        with self._lock:
            self.frames += 1
            row = self.particles.get(key)
            if row is None:
                row = ParticleRow(key, frame.sender, source, received.time, received.time)
                self.particles[key] = row
                if frame.sender == UNASSIGNED_ID:
                    self._note(
                        f"A particle without an id answered (id {UNASSIGNED_ID}); give it one "
                        f"with: setid {UNASSIGNED_ID} NEW_ID",
                        "warning",
                    )
            row.last_heard = max(row.last_heard, received.time)
            row.frames += 1
            message = frame.message
            if isinstance(message, Status):
                self._on_status(row, message, received.time)
            elif isinstance(message, Intensity):
                row.intensity = message.intensity
            elif isinstance(message, ParamValue):
                row.params[message.param] = (message.result, message.value)
                self._on_param_value(row, message, received.time)
        # Campaigns advance in poll(), on the caller's thread: commands never go out from the
        # receive thread, which must keep reading the radio.

    def _on_status(self, row: ParticleRow, status: Status, at: float) -> None:
        first_mismatch = status.definition_hash != self.host_hash and (
            row.status is None or row.status.definition_hash == self.host_hash
        )
        previous = row.status
        if previous is not None and reset_between(previous, status):
            self._on_reset(row, previous, status)
        row.status = status
        row.status_time = at
        row.intensity = status.intensity
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
                    self._conclude_query(query)
                return
        # Nobody here asked (another console, a late answer): one line of its own.
        self._note(_param_text(row.id, message))

    def _conclude_query(self, query: ParamQuery) -> None:
        query.done = True
        if query.target != BROADCAST_ID and query.replies:
            result, value = query.replies[query.target]
            text = f"Particle {query.target}: {param_name(query.param)} = {value} "
            text += f"({result_name(result)})"
            self._note(text, "info" if result == ParamResult.OK else "warning")
            return
        everyone_ok = query.replies and all(
            result == ParamResult.OK for result, _ in query.replies.values()
        )
        complete = query.expected <= set(query.replies)
        level = "info" if everyone_ok and complete else "warning"
        self._note(query.summary(self.param_timeout), level)

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

    def moving_ids(self) -> list[int]:
        """Ids of the particles whose latest STATUS shows them in a run (estimating, waiting,
        cycling or pausing), silent ones included: nothing says they stopped."""
        with self._lock:
            return sorted({row.id for row in self.particles.values() if row.moving})

    def new_notes(self) -> list[ModelNote]:
        """Notes added since the previous call (for a UI that appends them to a log pane)."""
        with self._lock:
            fresh = self.notes_written
            total = len(self.notes)
            count = min(fresh, total)
            self.notes_written = 0
            return list(self.notes)[total - count :]

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

            def confirms(row: ParticleRow, since: float) -> bool:
                return _fresh(row, since) and row.status is not None and row.status.run_id == run_id

            def needs_command(row: ParticleRow, since: float) -> bool:
                # It answered but is in another run: it missed START. The copy carries the same
                # run_id, so particles already in the run ignore it.
                return _fresh(row, since) and row.status is not None and row.status.run_id != run_id

            return self._launch(
                "START",
                message,
                (0.0,),
                self.start_interval,
                self.start_timeout,
                confirms,
                needs_command,
            )

    def stop(self) -> Campaign:
        """STOP as a burst (stop_burst), then PINGs until every known particle reports IDLE or
        DONE, or stop_timeout passes. STOP is repeated after the burst only while some particle
        has not answered STOPPING, IDLE or DONE since: a copy restarts the stop ramp of a
        particle that has it already."""
        with self._lock:
            self._cancel("START")
            self._cancel("STOP")
            self.run_active = False

            def confirms(row: ParticleRow, since: float) -> bool:
                return _fresh(row, since) and row.state in STOPPED_STATES

            def needs_command(row: ParticleRow, since: float) -> bool:
                return not (_fresh(row, since) and row.state in OBEYED_STOP_STATES)

            return self._launch(
                "STOP",
                Stop(),
                self.stop_burst,
                self.stop_interval,
                self.stop_timeout,
                confirms,
                needs_command,
            )

    def set_param(self, param: int, value: int, target: int = BROADCAST_ID) -> ParamQuery:
        """Sends SET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        return self._query("SET", SetParam(target=target, param=param, value=value), value)

    def get_param(self, param: int, target: int = BROADCAST_ID) -> ParamQuery:
        """Sends GET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        return self._query("GET", GetParam(target=target, param=param), None)

    def _query(self, kind: str, message: SetParam | GetParam, value: int | None) -> ParamQuery:
        with self._lock:
            if message.target == BROADCAST_ID:
                expected = {row.id for row in self.particles.values()}
            else:
                expected = {message.target}
            query = ParamQuery(kind, message.param, value, message.target, self.clock(), expected)
            if self._send(message):
                self.queries = [*(q for q in self.queries if not q.done), query]
            else:
                query.done = True
            return query

    def identify(self, target: int = BROADCAST_ID) -> None:
        self._send_once(Identify(target=target))

    def set_id(self, target: int, new_id: int) -> None:
        self._send_once(SetId(target=target, new_id=new_id))

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
                if not query.done and at - query.started >= self.param_timeout - CLOCK_SLACK_S:
                    self._conclude_query(query)
            quiet = self.packets == 0 and at - self.opened_at >= self.quiet_after
            if self.quiet_hint is not None and quiet:
                hint = f"Nothing heard for {self.quiet_after:g} s. {self.quiet_hint}"
                self._note(hint, "warning")
                self.quiet_hint = None

    # ---- internals -------------------------------------------------------------------------

    def _launch(
        self,
        name: str,
        command: Message,
        burst: tuple[float, ...],
        interval: float,
        timeout: float,
        confirms: Callable[[ParticleRow, float], bool],
        needs_command: Callable[[ParticleRow, float], bool],
    ) -> Campaign:
        now = self.clock()
        campaign = Campaign(
            name=name,
            command=command,
            started=now,
            burst=burst,
            interval=interval,
            timeout=timeout,
            pending=set(self.particles),
            confirms=confirms,
            needs_command=needs_command,
            next_send=now,
        )
        self.campaigns = [*self.campaigns[-7:], campaign]
        self._advance(campaign, now)
        return campaign

    def _cancel(self, name: str) -> None:
        for campaign in self.campaigns:
            if campaign.name == name and not campaign.done:
                campaign.done = True
                campaign.outcome = f"{name} superseded"

    def _advance(self, campaign: Campaign, now: float) -> None:
        # Judged on each particle's latest STATUS: one that confirmed can fall back (a late
        # copy of STOP finds it stopped and it reports STOPPING again, for a moment).
        for key in campaign.pending | campaign.confirmed:
            row = self.particles.get(key)
            if row is not None and campaign.confirms(row, campaign.started):
                campaign.pending.discard(key)
                campaign.confirmed.add(key)
            else:
                campaign.confirmed.discard(key)
                campaign.pending.add(key)
        # The whole burst goes out even when every known particle has confirmed: particles the
        # console has not heard of yet have no other chance of getting the command.
        if now - campaign.started >= campaign.timeout or (
            campaign.burst_sent and not campaign.pending
        ):
            self._conclude(campaign, now)
        elif now >= campaign.next_send - CLOCK_SLACK_S:
            self._send_round(campaign, now)

    def _conclude(self, campaign: Campaign, now: float) -> None:
        elapsed = now - campaign.started
        if campaign.pending:
            missing = [self.particles[key] for key in campaign.pending]
            self._finish(
                campaign,
                now,
                False,
                f"{campaign.name} not confirmed within {campaign.timeout:.0f} s by "
                f"particle(s) {_ids_text(missing)} ({len(campaign.confirmed)} confirmed); "
                "check they are switched on and in range, then try again",
            )
        elif campaign.confirmed:
            self._finish(
                campaign,
                now,
                True,
                f"{campaign.name} confirmed by all {len(campaign.confirmed)} particles "
                f"in {elapsed:.1f} s",
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
        rows = [self.particles[key] for key in campaign.pending]
        in_burst = index < len(campaign.burst)
        wanted = in_burst or any(campaign.needs_command(row, campaign.started) for row in rows)
        if wanted and not self._send(campaign.command, campaign):
            return
        if campaign.burst_sent:
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


def result_name(value: int) -> str:
    try:
        return ParamResult(value).name
    except ValueError:
        return f"result {value}"


def _param_text(particle: int, message: ParamValue) -> str:
    result = result_name(message.result)
    return f"Particle {particle}: {param_name(message.param)} = {message.value} ({result})"
