"""One receive thread per radio: decodes frames, fans everything out to listeners (log, console)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass
from typing import Self

from particlebot.closing import ClosedOnExit
from particlebot.protocol import (
    BASE_STATION_ID,
    DropEvent,
    Frame,
    Message,
    StreamDecoder,
    decode_frame,
    encode_frame,
)
from particlebot.radio import LinkEvent, LinkState, Packet, Radio, RadioError

_log = logging.getLogger(__name__)

# A partial frame older than this is dropped as truncated, like the firmware's 100 ms timeout: at
# 9600 baud a whole frame takes under 60 ms.
FRAME_TIMEOUT_S = 0.1


@dataclass(frozen=True)
class ReceivedFrame:
    time: float
    source: Hashable | None
    frame: Frame


@dataclass(frozen=True)
class Dropped:
    time: float
    event: DropEvent


@dataclass(frozen=True)
class SentFrame:
    time: float
    frame: Frame
    error: str | None = None


@dataclass(frozen=True)
class Note:
    """Something a person should read later in the log (e.g. which particles confirmed STOP)."""

    time: float
    text: str


class Listener:
    """Receives everything a Session sees; override what you need (python-can's Listener).

    Called from the session's receive thread (and from whichever thread sends), so
    implementations must be quick and thread-safe.
    """

    def on_packet(self, packet: Packet) -> None:
        """Raw bytes as the radio delivered them, before decoding."""

    def on_frame(self, received: ReceivedFrame) -> None:
        """A frame that passed the CRC check (its message may still be None)."""

    def on_dropped(self, dropped: Dropped) -> None:
        """Noise, a corrupted or truncated frame, an unknown type or a bad payload size."""

    def on_sent(self, sent: SentFrame) -> None:
        """A frame the base station sent (error set if the radio refused it)."""

    def on_link(self, event: LinkEvent) -> None:
        """The port vanished, came back, or the radio warns about its configuration."""

    def on_note(self, note: Note) -> None:
        """A remark worth keeping in the log."""

    def on_close(self) -> None:
        """The session ended; flush and close."""


class Session(ClosedOnExit):
    """Owns a radio, its frame decoder and the thread that reads it."""

    def __init__(self, radio: Radio, listeners: Iterable[Listener] = ()) -> None:
        self.radio = radio
        self._listeners: list[Listener] = list(listeners)
        self._listeners_lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._seq = 0
        self._pending_drops: list[DropEvent] = []
        self.decoder = StreamDecoder(on_drop=self._pending_drops.append)
        self._last_bytes: dict[Hashable | None, float] = {}
        self._decode_lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: RadioError | None = None
        radio.add_link_listener(self._on_link)

    # ---- lifecycle -------------------------------------------------------------------------

    def start(self) -> Self:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="radio-receive", daemon=True)
            self._thread.start()
        return self

    def close(self) -> None:
        """Stops receiving, closes the radio and tells every listener (each exactly once)."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5)
        self.radio.close()
        for listener in self._snapshot():
            try:
                listener.on_close()
            except Exception:  # one failing listener must not lose the others
                _log.exception("listener %r failed to stop", listener)

    def __enter__(self) -> Self:
        return self.start()  # a session starts receiving when its block begins

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def add_listener(self, listener: Listener) -> None:
        with self._listeners_lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        """Stops telling listener anything (not even on_close); one never added is ignored."""
        with self._listeners_lock:
            if listener in self._listeners:
                self._listeners.remove(listener)

    def now(self) -> float:
        return self.radio.now()

    # ---- sending ---------------------------------------------------------------------------

    def send(self, message: Message) -> SentFrame:
        """Frames and broadcasts message from the base station; RadioError if the radio refuses.

        The attempt is reported to listeners (and so logged) either way, after the send lock is
        released: a listener that sends, or waits for a thread that does, cannot deadlock.
        """
        with self._send_lock:
            seq = self._seq
            self._seq = (self._seq + 1) & 0xFF
            raw = encode_frame(message, BASE_STATION_ID, seq)
            frame = decode_frame(raw)
            try:
                self.radio.send(raw)
            except RadioError as exc:
                refused: RadioError | None = exc
                sent = SentFrame(self.now(), frame, str(exc))
            else:
                refused = None
                sent = SentFrame(self.now(), frame)
        self._emit(lambda listener: listener.on_sent(sent))
        if refused is not None:
            raise refused
        return sent

    def note(self, text: str) -> None:
        note = Note(self.now(), text)
        self._emit(lambda listener: listener.on_note(note))

    # ---- receiving -------------------------------------------------------------------------

    def pump(self) -> None:
        """Delivers every packet the radio holds now, on the caller's thread, instead of a
        receive thread (never both): a simulation stepped by its caller has all its packets
        in the radio's queue as soon as a step returns, so the caller sees them in order and
        the run is the same every time. RadioError if the radio failed."""
        if self._thread is not None:
            raise RuntimeError("pump() is for a session without a receive thread")
        while not self._stop.is_set():
            try:
                packet = self.radio.receive(timeout=0)
            except RadioError as exc:
                self._fail(exc)
                raise
            if packet is None:
                self._flush_stale(self.now())
                return
            self._handle(packet)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                packet = self.radio.receive(timeout=0.05)
            except RadioError as exc:
                self._fail(exc)
                return
            except Exception as exc:  # reported, then the thread ends cleanly
                _log.exception("radio receive failed")
                self._fail(RadioError(f"radio failed: {exc}"))
                return
            if packet is None:
                self._flush_stale(self.now())
                continue
            self._handle(packet)

    def _fail(self, error: RadioError) -> None:
        self.error = error
        event = LinkEvent(LinkState.CLOSED, str(error), self.now())
        self._emit(lambda listener: listener.on_link(event))

    def _handle(self, packet: Packet) -> None:
        self._emit(lambda listener: listener.on_packet(packet))
        with self._decode_lock:
            last = self._last_bytes.get(packet.source)
            frames: list[Frame] = []
            if last is not None and packet.time - last > FRAME_TIMEOUT_S:
                frames += self.decoder.flush(packet.source)
            self._last_bytes[packet.source] = packet.time
            frames += self.decoder.feed(packet.data, packet.source)
            drops = self._take_drops()
        self._deliver(packet.time, packet.source, drops, frames)

    def _flush_stale(self, now: float, everything: bool = False) -> None:
        with self._decode_lock:
            flushed: list[tuple[Hashable | None, list[Frame]]] = []
            for source in self.decoder.sources():
                last = self._last_bytes.get(source)
                if everything or last is None or now - last > FRAME_TIMEOUT_S:
                    flushed.append((source, self.decoder.flush(source)))
            drops = self._take_drops()
        self._deliver(now, None, drops, [])
        for source, frames in flushed:
            self._deliver(now, source, [], frames)

    def _take_drops(self) -> list[DropEvent]:
        drops = list(self._pending_drops)
        self._pending_drops.clear()
        return drops

    def _deliver(
        self,
        time: float,
        source: Hashable | None,
        drops: list[DropEvent],
        frames: list[Frame],
    ) -> None:
        for event in drops:
            self._emit_dropped(Dropped(time, event))
        for frame in frames:
            self._emit_frame(ReceivedFrame(time, source, frame))

    def _emit_dropped(self, dropped: Dropped) -> None:
        self._emit(lambda listener: listener.on_dropped(dropped))

    def _emit_frame(self, received: ReceivedFrame) -> None:
        self._emit(lambda listener: listener.on_frame(received))

    def _on_link(self, event: LinkEvent) -> None:
        if event.state is LinkState.LOST:
            # Whatever half-frame the port held is gone with it.
            self._flush_stale(event.time, everything=True)
        self._emit(lambda listener: listener.on_link(event))

    def _snapshot(self) -> list[Listener]:
        with self._listeners_lock:
            return list(self._listeners)

    def _emit(self, call: Callable[[Listener], None]) -> None:
        """call(listener) for every listener, e.g. lambda listener: listener.on_frame(received);
        the callbacks are named in the code, so a type checker and a rename see each one."""
        for listener in self._snapshot():
            try:
                call(listener)
            except Exception:  # a faulty listener must not stop reception
                _log.exception("listener %r failed", listener)
