"""Hand-written stand-ins for the tests: a radio fed by the test, and a manual clock."""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Hashable
from typing import Self

from particlebot.protocol import (
    DEFINITION_HASH,
    Frame,
    Method,
    State,
    Status,
    decode_frame,
    encode_frame,
)
from particlebot.radio import LinkEvent, LinkState, Packet, PortLostError, Radio, RadioUrl
from particlebot.session import Dropped, Listener, ReceivedFrame, SentFrame


class ManualClock:
    def __init__(self, start: float = 1000.0) -> None:
        self.now = start

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


class FakeRadio(Radio):
    """Packets come from inject(); sent frames are kept in `sent`. Time is a ManualClock."""

    def __init__(self, clock: ManualClock | None = None) -> None:
        super().__init__("fake://")
        self.clock = clock or ManualClock()
        self.incoming: queue.Queue[Packet] = queue.Queue()
        self.sent: list[bytes] = []
        self.sent_event = threading.Condition()
        self.fail_sends = False

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        raise NotImplementedError

    def inject(self, data: bytes, source: Hashable | None = None, at: float | None = None) -> None:
        self.incoming.put(Packet(data, source, self.clock() if at is None else at))

    def send(self, data: bytes) -> None:
        if self.fail_sends:
            raise PortLostError("fake port is gone")
        with self.sent_event:
            self.sent.append(data)
            self.sent_event.notify_all()

    def sent_frames(self) -> list[Frame]:
        with self.sent_event:
            return [decode_frame(data) for data in self.sent]

    def receive(self, timeout: float | None = None) -> Packet | None:
        try:
            return self.incoming.get(timeout=timeout)
        except queue.Empty:
            return None

    def now(self) -> float:
        return self.clock()

    def lose(self, message: str = "gone") -> None:
        self._set_link(LinkState.LOST, message)


class Recorder(Listener):
    """Keeps everything a session delivers and lets a test wait for it."""

    def __init__(self) -> None:
        self.packets: list[Packet] = []
        self.frames: list[ReceivedFrame] = []
        self.dropped: list[Dropped] = []
        self.sent: list[SentFrame] = []
        self.links: list[LinkEvent] = []
        self.closed = False
        self.changed = threading.Condition()

    def _add(self, items: list, item: object) -> None:
        with self.changed:
            items.append(item)
            self.changed.notify_all()

    def on_packet(self, packet: Packet) -> None:
        self._add(self.packets, packet)

    def on_frame(self, received: ReceivedFrame) -> None:
        self._add(self.frames, received)

    def on_dropped(self, dropped: Dropped) -> None:
        self._add(self.dropped, dropped)

    def on_sent(self, sent: SentFrame) -> None:
        self._add(self.sent, sent)

    def on_link(self, event: LinkEvent) -> None:
        self._add(self.links, event)

    def on_close(self) -> None:
        self.closed = True

    def wait(self, predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
        with self.changed:
            return self.changed.wait_for(predicate, timeout)


def wait_until(predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
    """Polls a condition that no listener signals (e.g. a file's contents)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return predicate()


def status_message(**fields: int | tuple[int, ...]) -> Status:
    """A STATUS with plausible values; keyword arguments override them."""
    values: dict[str, int | tuple[int, ...]] = {
        "state": int(State.IDLE),
        "method": int(Method.COUNTING),
        "run_id": 0,
        "s_n": 0,
        "group_size": 1,
        "sensor_faults": 0,
        "intensity": 900,
        "sensors": (900,) * 6,
        "cycle_phase": 0,
        "radius_um": 77500,
        "uptime_ms": 1000,
        "definition_hash": DEFINITION_HASH,
        "rx_frames": 0,
        "rx_bad_crc": 0,
        "rx_bad_length": 0,
        "rx_skipped_bytes": 0,
        "resets": 1,
        "last_reset_cause": 1,
        "servo_pulse_us": 1000,
    }
    values.update(fields)
    return Status(**values)  # type: ignore[arg-type]


def status_frame(sender: int, seq: int = 0, **fields: int | tuple[int, ...]) -> bytes:
    return encode_frame(status_message(**fields), sender, seq)
