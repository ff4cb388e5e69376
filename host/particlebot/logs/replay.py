"""A radio that plays a session log back, so `particlebot replay` shows it in the same console."""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path
from typing import Self

from particlebot.logs.jsonl import LogError, RecordReader, load_log
from particlebot.radio import (
    InvalidRadioUrlError,
    LinkState,
    Packet,
    Radio,
    RadioUrl,
    ReadOnlyRadioError,
)


class ReplayRadio(Radio):
    """Hands out the raw packets a log recorded (replay://logs/x.jsonl?speed=4), with their
    original spacing divided by speed (speed=max: all at once). Everything downstream (decoding,
    bad-frame counts, the console) runs exactly as it did live."""

    faults_on_link = False  # it replays what was heard: nothing to lose or delay

    def __init__(self, path: Path, speed: float = 1.0, *, url: str | None = None) -> None:
        super().__init__(url or f"replay://{path}")
        if not speed > 0:  # NaN too
            raise InvalidRadioUrlError(f"{self.url}: speed must be positive (or max)")
        self.path = path
        self.speed = speed
        self._items: list[tuple[float, Packet | tuple[LinkState, str]]] = []
        ended: float | None = None
        for number, record in load_log(path):
            kind = record.get("kind")
            if kind == "rx":
                fields = RecordReader(path, number, record)
                at = fields.number("t")
                data = fields.hex_bytes("hex")
                source = fields.optional_text("src")
                self._items.append((at, Packet(data=data, source=source, time=at)))
            elif kind == "link" and record.get("state") in ("lost", "connected"):
                fields = RecordReader(path, number, record)
                at = fields.number("t")
                self._items.append((at, (LinkState(record["state"]), str(record.get("text", "")))))
            elif kind == "end":
                ended = RecordReader(path, number, record).number("t")
        self.start_time = self._items[0][0] if self._items else time.time()
        last = self._items[-1][0] if self._items else self.start_time
        self.end_time = last if ended is None else max(ended, last)
        """Where the replay's clock stops: the session's end, so that a finished replay goes on
        showing how things stood then (not every particle SILENT, as the wall clock would)."""
        self._next = 0
        self._clock = self.start_time
        self._wall_start: float | None = None
        self._closed = threading.Event()

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        url.check_options({"speed"})
        try:
            return cls(Path(url.target), url.get_speed(), url=url.text)
        except LogError as exc:
            raise InvalidRadioUrlError(str(exc)) from None

    @property
    def finished(self) -> bool:
        return self._next >= len(self._items)

    @property
    def span_s(self) -> float:
        """Seconds of the log from its first to its last replayed item."""
        return self._items[-1][0] - self.start_time if self._items else 0.0

    @property
    def position_s(self) -> float:
        """How far into span_s the replay has got."""
        return self._clock - self.start_time

    @property
    def total_packets(self) -> int:
        return sum(1 for _, item in self._items if isinstance(item, Packet))

    def now(self) -> float:
        if self._wall_start is None or math.isinf(self.speed):
            return self._clock
        elapsed = (time.monotonic() - self._wall_start) * self.speed
        return min(self.start_time + elapsed, self.end_time)

    def send(self, data: bytes) -> None:
        raise ReadOnlyRadioError("This is a replay of a log; nothing can be sent to the particles.")

    def receive(self, timeout: float | None = None) -> Packet | None:
        if self._wall_start is None:
            self._wall_start = time.monotonic()
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._closed.is_set() and not self.finished:
            at, item = self._items[self._next]
            wait = 0.0 if math.isinf(self.speed) else (at - self.now()) / self.speed
            if wait > 0:
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return None
                self._closed.wait(wait if left is None else min(wait, left))
                continue
            self._next += 1
            self._clock = at
            if isinstance(item, Packet):
                return item
            self._set_link(*item)
        if deadline is not None:
            self._closed.wait(max(0.0, deadline - time.monotonic()))
        return None

    def close(self) -> None:
        self._closed.set()
        super().close()
