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
from particlebot.radio import LinkEvent, LinkState, Packet, RadioError
from particlebot.session import Dropped, Listener, ReceivedFrame, SentFrame

# STATUS comes every STATUS_PERIOD_MS (2 s by default, +-25 %): three missed ones mean trouble.
SILENT_AFTER_S = 6.5
STOPPED_STATES = frozenset({State.IDLE, State.DONE})
OBEYED_STOP_STATES = frozenset({State.STOPPING, State.IDLE, State.DONE})


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
    def bad_frames(self) -> int | None:
        """Frames that reached the particle damaged, as it reports them."""
        if self.status is None:
            return None
        return self.status.rx_bad_crc + self.status.rx_bad_length


@dataclass
class Campaign:
    """A command broadcast repeatedly until every targeted particle confirms it, or time runs out.

    802.15.4 broadcasts are not acknowledged, so the only proof a particle obeyed is a STATUS it
    sent afterwards.
    """

    name: str
    messages: list[Message]
    started: float
    interval: float
    timeout: float
    pending: set[str]
    confirms: Callable[[ParticleRow, float], bool]
    acknowledges: Callable[[ParticleRow, float], bool] | None = None
    """Obeyed but not finished yet (STOPPING): stop repeating `messages`, send `followup`."""
    followup: list[Message] = field(default_factory=list)
    confirmed: set[str] = field(default_factory=set)
    acknowledged: set[str] = field(default_factory=set)
    next_send: float = 0.0
    sends: int = 0
    done: bool = False
    success: bool = False
    outcome: str = ""
    finished_at: float | None = None


@dataclass(frozen=True)
class ModelNote:
    time: float
    text: str
    level: str = "info"  # info, warning, error


def _fresh(row: ParticleRow, since: float) -> bool:
    """Whether row's last STATUS was received at or after since."""
    return row.status_time is not None and row.status_time >= since


def _ids_text(rows: list[ParticleRow]) -> str:
    return ", ".join(str(row.id) for row in sorted(rows, key=lambda r: r.id))


class ConsoleModel(Listener):
    """Per-particle state from the frames a session delivers, and the commands a person gives."""

    def __init__(
        self,
        sink: CommandSink | None,
        clock: Callable[[], float],
        *,
        host_hash: int = DEFINITION_HASH,
        silent_after: float = SILENT_AFTER_S,
        stop_interval: float = 1.0,
        stop_timeout: float = 10.0,
        start_interval: float = 2.5,
        start_timeout: float = 8.0,
    ) -> None:
        self.sink = sink
        self.clock = clock
        self.host_hash = host_hash
        self.silent_after = silent_after
        self.stop_interval = stop_interval
        self.stop_timeout = stop_timeout
        self.start_interval = start_interval
        self.start_timeout = start_timeout
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
                self._note(_param_text(row.id, message))
        self.poll(received.time)

    def _on_status(self, row: ParticleRow, status: Status, at: float) -> None:
        first_mismatch = status.definition_hash != self.host_hash and (
            row.status is None or row.status.definition_hash == self.host_hash
        )
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

    def new_notes(self) -> list[ModelNote]:
        """Notes added since the previous call (for a UI that appends them to a log pane)."""
        with self._lock:
            fresh = self.notes_written
            total = len(self.notes)
            count = min(fresh, total)
            self.notes_written = 0
            return list(self.notes)[total - count :]

    def active(self, name: str) -> Campaign | None:
        with self._lock:
            for campaign in self.campaigns:
                if campaign.name == name and not campaign.done:
                    return campaign
        return None

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
                return (
                    row.status is not None
                    and row.status_time is not None
                    and row.status_time >= since
                    and row.status.run_id == run_id
                )

            return self._launch(
                "START", [message], self.start_interval, self.start_timeout, confirms
            )

    def stop(self) -> Campaign:
        """STOP (and PING, so answers come at once) until every known particle has answered with
        STOPPING, IDLE or DONE; then PING alone until each reports IDLE or DONE, or stop_timeout
        passes. (STOP is not repeated to particles that obeyed: it would restart their STOPPING.)
        """
        with self._lock:
            self._cancel("START")
            self._cancel("STOP")

            def confirms(row: ParticleRow, since: float) -> bool:
                return _fresh(row, since) and row.state in STOPPED_STATES

            def acknowledges(row: ParticleRow, since: float) -> bool:
                return _fresh(row, since) and row.state in OBEYED_STOP_STATES

            return self._launch(
                "STOP",
                [Stop(), Ping(target=BROADCAST_ID)],
                self.stop_interval,
                self.stop_timeout,
                confirms,
                acknowledges=acknowledges,
                followup=[Ping(target=BROADCAST_ID)],
            )

    def set_param(self, param: int, value: int, target: int = BROADCAST_ID) -> None:
        self._send_once(SetParam(target=target, param=param, value=value))

    def get_param(self, param: int, target: int = BROADCAST_ID) -> None:
        self._send_once(GetParam(target=target, param=param))

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

    # ---- internals -------------------------------------------------------------------------

    def _launch(
        self,
        name: str,
        messages: list[Message],
        interval: float,
        timeout: float,
        confirms: Callable[[ParticleRow, float], bool],
        *,
        acknowledges: Callable[[ParticleRow, float], bool] | None = None,
        followup: list[Message] | None = None,
    ) -> Campaign:
        now = self.clock()
        campaign = Campaign(
            name=name,
            messages=messages,
            started=now,
            interval=interval,
            timeout=timeout,
            pending=set(self.particles),
            confirms=confirms,
            acknowledges=acknowledges,
            followup=followup or [],
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
        for key in list(campaign.pending):
            row = self.particles.get(key)
            if row is None:
                continue
            if campaign.confirms(row, campaign.started):
                campaign.pending.discard(key)
                campaign.confirmed.add(key)
            elif campaign.acknowledges is not None and campaign.acknowledges(row, campaign.started):
                campaign.acknowledged.add(key)
        elapsed = now - campaign.started
        if not campaign.pending and campaign.confirmed:
            self._finish(
                campaign,
                now,
                True,
                f"{campaign.name} confirmed by all {len(campaign.confirmed)} particles "
                f"in {elapsed:.1f} s",
            )
            return
        if elapsed >= campaign.timeout:
            if campaign.confirmed or campaign.pending:
                missing = [self.particles[key] for key in campaign.pending]
                self._finish(
                    campaign,
                    now,
                    False,
                    f"{campaign.name} not confirmed within {campaign.timeout:.0f} s by "
                    f"particle(s) {_ids_text(missing)} ({len(campaign.confirmed)} confirmed); "
                    "check they are switched on and in range, then try again",
                )
            else:
                self._finish(
                    campaign, now, True, f"{campaign.name} sent; no particles known to confirm it"
                )
            return
        if now >= campaign.next_send:
            campaign.next_send = now + campaign.interval
            campaign.sends += 1
            everyone_obeyed = campaign.pending <= campaign.acknowledged and campaign.sends > 1
            for message in campaign.followup if everyone_obeyed else campaign.messages:
                if not self._send(message):
                    break

    def _finish(self, campaign: Campaign, now: float, success: bool, text: str) -> None:
        campaign.done = True
        campaign.success = success
        campaign.outcome = text
        campaign.finished_at = now
        self._note(text, "info" if success else "error")

    def _send_once(self, message: Message) -> None:
        with self._lock:
            self._send(message)

    def _send(self, message: Message) -> bool:
        if self.sink is None:
            self._note("Nothing can be sent: no radio", "error", log=False)
            return False
        try:
            self.sink.send(message)
        except RadioError as exc:
            self._note(f"Could not send {type(message).__name__}: {exc}", "error", log=False)
            return False
        return True

    def _note(self, text: str, level: str = "info", *, log: bool = True) -> None:
        self.notes.append(ModelNote(self.clock(), text, level))
        self.notes_written += 1
        if log and self.sink is not None:
            self.sink.note(text)


def _param_text(particle: int, message: ParamValue) -> str:
    try:
        result = ParamResult(message.result).name
    except ValueError:
        result = f"result {message.result}"
    return f"Particle {particle}: {param_name(message.param)} = {message.value} ({result})"
