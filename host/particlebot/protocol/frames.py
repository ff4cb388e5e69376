"""Frame codec of the radio link: CRC-16, frame encoding and a resynchronising stream decoder.

The stream decoder accepts exactly the frames the firmware's FrameParser (frame.cpp) accepts: it
hunts for the sync marker, and when a candidate fails (LEN over max_payload, CRC mismatch, or
truncated by flush) it rescans from the byte after that candidate's sync marker, so a real frame
hidden inside a corrupted one is still found.
"""

from __future__ import annotations

import binascii
import enum
from collections import deque
from collections.abc import Callable, Hashable
from dataclasses import dataclass, fields
from functools import cached_property

from particlebot.errors import ParticlebotError
from particlebot.protocol.generated import (
    FRAME_OVERHEAD,
    MAX_PAYLOAD,
    MESSAGES,
    SYNC,
    Message,
    MessageType,
    PayloadError,
)

_SYNC0 = SYNC[0]
_HEADER = 4  # LEN TYPE SENDER SEQ


def crc16(data: bytes | bytearray | memoryview, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor) of data.

    Pass a previous result as crc to continue over more data.
    """
    # binascii's CRC-CCITT is this very polynomial, unreflected, with a caller-chosen start value.
    return binascii.crc_hqx(data, crc)


class DropReason(enum.Enum):
    """Why bytes or a frame did not become a message."""

    SKIPPED = "skipped"
    """Bytes outside any frame while hunting for the sync marker."""
    BAD_LENGTH = "bad_length"
    """LEN over max_payload; the bytes after the sync marker are rescanned."""
    BAD_CRC = "bad_crc"
    """CRC mismatch; the bytes after the sync marker are rescanned."""
    TRUNCATED = "truncated"
    """flush() found a partial frame; the bytes after its sync marker are rescanned."""
    UNKNOWN_TYPE = "unknown_type"
    """A valid frame of a type this definition does not know (still returned, message None)."""
    BAD_PAYLOAD = "bad_payload"
    """A valid frame whose payload size does not fit its type (still returned, message None)."""


class FrameError(ParticlebotError, ValueError):
    """A byte string is not exactly one valid frame, or a frame cannot be built."""

    def __init__(self, reason: DropReason, detail: str) -> None:
        super().__init__(f"{reason.value}: {detail}")
        self.reason = reason


def encode_raw_frame(frame_type: int, sender: int, seq: int, payload: bytes) -> bytes:
    """One frame around an arbitrary payload (also for types this definition does not know)."""
    for name, value in (("type", frame_type), ("sender", sender), ("seq", seq)):
        if not 0 <= value <= 0xFF:
            raise FrameError(DropReason.BAD_PAYLOAD, f"{name} {value} is not a byte")
    if len(payload) > MAX_PAYLOAD:
        raise FrameError(
            DropReason.BAD_LENGTH, f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}"
        )
    body = bytes((len(payload), frame_type, sender, seq)) + payload
    return SYNC + body + crc16(body).to_bytes(2, "little")


def encode_frame(message: Message, sender: int, seq: int) -> bytes:
    """The frame carrying message from sender with sequence number seq."""
    return encode_raw_frame(message.MESSAGE_TYPE, sender, seq, message.encode_payload())


@dataclass(frozen=True)
class Frame:
    """One frame that passed the CRC check."""

    type: int
    sender: int
    seq: int
    payload: bytes

    @cached_property
    def message(self) -> Message | None:
        """The decoded message; None for an unknown type or a payload of the wrong size."""
        cls = MESSAGES.get(self.type)
        if cls is None:
            return None
        try:
            return cls.decode_payload(self.payload)
        except PayloadError:
            return None

    @cached_property
    def raw(self) -> bytes:
        """The frame's bytes on the air."""
        return encode_raw_frame(self.type, self.sender, self.seq, self.payload)

    @property
    def type_name(self) -> str:
        """The message type's name, or its number in hex when this definition does not know it."""
        try:
            return MessageType(self.type).name
        except ValueError:
            return f"0x{self.type:02X}"


def decode_frame(data: bytes | bytearray) -> Frame:
    """The frame data holds, which must be exactly one valid frame; FrameError otherwise."""
    if len(data) < FRAME_OVERHEAD or data[:2] != SYNC:
        raise FrameError(DropReason.SKIPPED, "does not start with the sync marker")
    length = data[2]
    if length > MAX_PAYLOAD:
        raise FrameError(DropReason.BAD_LENGTH, f"LEN {length} exceeds {MAX_PAYLOAD}")
    if len(data) != length + FRAME_OVERHEAD:
        raise FrameError(
            DropReason.TRUNCATED if len(data) < length + FRAME_OVERHEAD else DropReason.SKIPPED,
            f"{len(data)} bytes for a frame of {length + FRAME_OVERHEAD}",
        )
    end = length + 6
    if crc16(data[2:end]) != data[end] | data[end + 1] << 8:
        raise FrameError(DropReason.BAD_CRC, "CRC mismatch")
    return Frame(data[3], data[4], data[5], bytes(data[6:end]))


@dataclass
class DecodeStats:
    """Counters of a StreamDecoder; every received byte is in exactly one of: an accepted frame,
    the two sync bytes of a dropped candidate (bad_crc, bad_length, truncated), skipped_bytes, or
    a buffer still waiting for more bytes."""

    frames: int = 0
    """Frames that passed the CRC check (unknown_type and bad_payload ones included)."""
    bad_crc: int = 0
    bad_length: int = 0
    truncated: int = 0
    skipped_bytes: int = 0
    unknown_type: int = 0
    bad_payload: int = 0

    def as_dict(self) -> dict[str, int]:
        return {item.name: getattr(self, item.name) for item in fields(self)}


@dataclass(frozen=True)
class DropEvent:
    """What a StreamDecoder dropped (or could not understand), why, and from which source."""

    reason: DropReason
    source: Hashable
    data: bytes
    """The bytes concerned: the skipped run, or the failed candidate from its sync marker on."""


class StreamDecoder:
    """Reassembles frames from byte chunks, one buffer per source.

    A transparent XBee may split one frame over several RF packets, and packets of different
    senders interleave, so each source (e.g. the sender's radio address) gets its own buffer.
    """

    def __init__(
        self,
        on_drop: Callable[[DropEvent], None] | None = None,
        keep_events: int = 256,
    ) -> None:
        self.stats = DecodeStats()
        self.on_drop = on_drop
        self.events: deque[DropEvent] = deque(maxlen=keep_events)
        """The most recent drop events, oldest first."""
        self._buffers: dict[Hashable, bytearray] = {}

    def feed(self, data: bytes | bytearray, source: Hashable = None) -> list[Frame]:
        """Adds bytes received from source; returns the frames they complete, in order."""
        buffer = self._buffers.get(source)
        if buffer is None:
            buffer = self._buffers[source] = bytearray()
        buffer += data
        return self._scan(buffer, source, final=False)

    def flush(self, source: Hashable = None) -> list[Frame]:
        """Ends source's stream (e.g. after a silence): a partial frame is dropped as truncated and
        the bytes after its sync marker are rescanned; returns any frame found in them."""
        buffer = self._buffers.pop(source, None)
        if not buffer:
            return []
        return self._scan(buffer, source, final=True)

    def buffered(self, source: Hashable = None) -> int:
        """Bytes of source waiting for the rest of a frame."""
        return len(self._buffers.get(source, b""))

    def sources(self) -> list[Hashable]:
        """Sources with bytes waiting for the rest of a frame."""
        return [source for source, buffer in self._buffers.items() if buffer]

    def _drop(self, reason: DropReason, source: Hashable, data: bytes) -> None:
        event = DropEvent(reason, source, data)
        self.events.append(event)
        if self.on_drop is not None:
            self.on_drop(event)

    def _skip(self, source: Hashable, data: bytes) -> None:
        self.stats.skipped_bytes += len(data)
        self._drop(DropReason.SKIPPED, source, data)

    def _scan(self, buffer: bytearray, source: Hashable, final: bool) -> list[Frame]:
        frames: list[Frame] = []
        stats = self.stats
        size = len(buffer)
        start = 0
        while start < size:
            marker = buffer.find(SYNC, start)
            if marker < 0:
                # A last SYNC0 may be completed by the next chunk.
                end = size - 1 if not final and buffer[size - 1] == _SYNC0 else size
                if end > start:
                    self._skip(source, bytes(buffer[start:end]))
                start = end
                break
            if marker > start:
                self._skip(source, bytes(buffer[start:marker]))
            start = marker
            if marker + 2 >= size:
                if not final:
                    break
                stats.truncated += 1
                self._drop(DropReason.TRUNCATED, source, bytes(buffer[marker:]))
                start = marker + 2
                continue
            length = buffer[marker + 2]
            if length > MAX_PAYLOAD:
                stats.bad_length += 1
                self._drop(DropReason.BAD_LENGTH, source, bytes(buffer[marker : marker + 3]))
                start = marker + 2
                continue
            crc_at = marker + 2 + _HEADER + length
            if crc_at + 2 > size:
                if not final:
                    break
                stats.truncated += 1
                self._drop(DropReason.TRUNCATED, source, bytes(buffer[marker:]))
                start = marker + 2
                continue
            if binascii.crc_hqx(buffer[marker + 2 : crc_at], 0xFFFF) != (
                buffer[crc_at] | buffer[crc_at + 1] << 8
            ):
                stats.bad_crc += 1
                self._drop(DropReason.BAD_CRC, source, bytes(buffer[marker : crc_at + 2]))
                start = marker + 2
                continue
            frame_type = buffer[marker + 3]
            frame = Frame(
                frame_type,
                buffer[marker + 4],
                buffer[marker + 5],
                bytes(buffer[marker + 6 : crc_at]),
            )
            stats.frames += 1
            cls = MESSAGES.get(frame_type)
            if cls is None:
                stats.unknown_type += 1
                self._drop(DropReason.UNKNOWN_TYPE, source, bytes(buffer[marker : crc_at + 2]))
            elif length != cls.PAYLOAD_SIZE:
                stats.bad_payload += 1
                self._drop(DropReason.BAD_PAYLOAD, source, bytes(buffer[marker : crc_at + 2]))
            frames.append(frame)
            start = crc_at + 2
        del buffer[:start]
        if not buffer:
            self._buffers.pop(source, None)
        return frames


__all__ = [
    "DecodeStats",
    "DropEvent",
    "DropReason",
    "Frame",
    "FrameError",
    "StreamDecoder",
    "crc16",
    "decode_frame",
    "encode_frame",
    "encode_raw_frame",
]
