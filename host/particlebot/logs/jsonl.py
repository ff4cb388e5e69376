"""JSON-lines session log: one object per line, each written and flushed as it happens."""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
import os
import threading
import time
from collections.abc import Callable, Hashable, Iterator
from pathlib import Path
from typing import Any, cast

from particlebot.errors import ParticlebotError
from particlebot.protocol import DEFINITION_HASH, Frame, Message
from particlebot.radio import LinkEvent, Packet
from particlebot.session import Dropped, Listener, Note, ReceivedFrame, SentFrame

FORMAT_VERSION = 1

Record = dict[str, Any]


def default_log_path(log_dir: Path, now: datetime.datetime | None = None) -> Path:
    """log_dir/YYYYmmdd-HHMMSS.jsonl, never an existing file."""
    stamp = (now or datetime.datetime.now()).strftime("%Y%m%d-%H%M%S")
    path = log_dir / f"{stamp}.jsonl"
    counter = 1
    while path.exists():
        path = log_dir / f"{stamp}-{counter}.jsonl"
        counter += 1
    return path


def source_text(source: Hashable | None) -> str | None:
    return None if source is None else str(source)


def message_fields(message: Message) -> dict[str, Any]:
    """A message's fields by name, arrays as lists (JSON-ready)."""
    values = dataclasses.asdict(cast(Any, message))
    return {name: list(v) if isinstance(v, tuple) else v for name, v in values.items()}


def frame_record(frame: Frame) -> Record:
    """sender, type, seq, raw bytes and decoded fields of a frame, JSON-ready."""
    message = frame.message
    record: Record = {
        "sender": frame.sender,
        "type": frame.type_name,
        "type_id": frame.type,
        "seq": frame.seq,
        "hex": frame.raw.hex(),
    }
    if message is not None:
        record["fields"] = message_fields(message)
    return record


class JsonlWriter(Listener):
    """Logs everything a session sees. Each line goes out in a single write() on an unbuffered
    file, so a crash or a kill leaves every earlier line whole; fsync=True also survives a power
    cut, at the cost of a disk sync per line."""

    def __init__(
        self,
        path: Path,
        *,
        radio: str = "",
        fsync: bool = False,
        clock: Callable[[], float] = time.time,
    ) -> None:
        """clock: the session's clock (the radio's), which stamps records that carry no time of
        their own; a simulated radio's runs ahead of the wall clock when sped up."""
        self.path = path
        self.fsync = fsync
        self.clock = clock
        self.latest = -math.inf
        """The latest time written: the end record is never stamped before it."""
        self.lines = 0
        self._lock = threading.Lock()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._fd: int | None = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        except OSError as exc:
            in_the_way = _file_in_the_way(path.parent)
            why = f"{in_the_way} is a file" if in_the_way else exc.strerror or str(exc)
            raise LogError(
                f"cannot write the session log {path} ({why}); give --log-dir a folder you can "
                "write to"
            ) from None
        self.write(
            {
                "kind": "session",
                "format": FORMAT_VERSION,
                "program": "particlebot",
                "radio": radio,
                "host_hash": f"0x{DEFINITION_HASH:08X}",
                "started": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            }
        )

    def write(self, record: Record, at: float | None = None) -> None:
        t = round(self.clock() if at is None else at, 6)
        line = {"t": t, **record}
        data = (json.dumps(line, separators=(",", ":")) + "\n").encode()
        with self._lock:
            if self._fd is None:
                return
            self.latest = max(self.latest, t)
            os.write(self._fd, data)
            if self.fsync:
                os.fsync(self._fd)
            self.lines += 1

    def on_packet(self, packet: Packet) -> None:
        self.write(
            {"kind": "rx", "src": source_text(packet.source), "hex": packet.data.hex()},
            packet.time,
        )

    def on_frame(self, received: ReceivedFrame) -> None:
        self.write(
            {"kind": "frame", "src": source_text(received.source), **frame_record(received.frame)},
            received.time,
        )

    def on_dropped(self, dropped: Dropped) -> None:
        event = dropped.event
        self.write(
            {
                "kind": "drop",
                "src": source_text(event.source),
                "reason": event.reason.value,
                "hex": event.data.hex(),
            },
            dropped.time,
        )

    def on_sent(self, sent: SentFrame) -> None:
        record: Record = {"kind": "tx", **frame_record(sent.frame)}
        if sent.error is not None:
            record["error"] = sent.error
        self.write(record, sent.time)

    def on_link(self, event: LinkEvent) -> None:
        self.write({"kind": "link", "state": event.state.value, "text": event.message}, event.time)

    def on_note(self, note: Note) -> None:
        self.write({"kind": "note", "text": note.text}, note.time)

    def on_close(self) -> None:
        # Records arrive from several threads, each stamped when it happened: the last one can be
        # stamped a little after the clock reads now. The end stays the end.
        ended = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        self.write(
            {"kind": "end", "lines": self.lines + 1, "ended": ended},
            max(self.clock(), self.latest),
        )
        with self._lock:
            fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)


def _file_in_the_way(folder: Path) -> Path | None:
    """The file that stands where folder, or a folder above it, should be ("File exists" and
    "Not a directory" name neither)."""
    for place in (*reversed(folder.parents), folder):
        if place.exists() and not place.is_dir():
            return place
    return None


class LogError(ParticlebotError):
    """A log that cannot be written or read; the message names the file and says why."""


class LogFormatError(LogError, ValueError):
    """A line of a log that is not what the format says."""


def read_numbered(path: Path) -> Iterator[tuple[int, Record]]:
    """(line number, record) of a log in order. A torn last line (power cut without fsync) is
    skipped; a bad line anywhere else raises LogFormatError naming it, and a file that cannot be
    read LogError."""
    try:
        if not path.exists():
            raise LogError(f"no log file {path}")
        if not path.is_file():
            # A directory cannot be read as a log, and a FIFO or device would block or never end.
            raise LogError(f"cannot read the log {path}: not a regular file")
        with path.open("rb") as file:
            lines = file.read().split(b"\n")
    except OSError as exc:
        raise LogError(f"cannot read the log {path}: {exc.strerror or exc}") from None
    last = len(lines) - 1
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError as exc:
            if number - 1 == last:
                return
            raise LogFormatError(f"{path}:{number}: not a JSON object ({exc})") from exc
        if not isinstance(record, dict):
            raise LogFormatError(f"{path}:{number}: not a JSON object")
        yield number, record


def read_log(path: Path) -> Iterator[Record]:
    """The records of a log in order (see read_numbered)."""
    for _, record in read_numbered(path):
        yield record


def load_log(path: Path) -> list[tuple[int, Record]]:
    """Every (line number, record) of a log; LogError if it holds none (an empty file, or one a
    power cut left full of NUL bytes), since nothing can be made of it."""
    records = list(read_numbered(path))
    if not records:
        raise LogError(f"{path} holds no log records (empty, or not a particlebot log)")
    return records


class RecordReader:
    """Typed access to one record's keys; a key of the wrong type raises LogFormatError naming
    the file, line and key, so a damaged log is reported instead of crashing its reader."""

    def __init__(self, path: Path, number: int, record: Record) -> None:
        self.where = f"{path}:{number}"
        self.record = record

    def _wrong(self, key: str, wanted: str) -> LogFormatError:
        value = json.dumps(self.record.get(key))
        return LogFormatError(f"{self.where}: '{key}' must be {wanted}, not {value[:40]}")

    def number(self, key: str) -> float:
        value = self.record.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self._wrong(key, "a number")
        if not math.isfinite(value):
            raise self._wrong(key, "a finite number")
        return float(value)

    def integer(self, key: str) -> int:
        value = self.record.get(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self._wrong(key, "a whole number")
        return value

    def text(self, key: str) -> str:
        value = self.record.get(key)
        if not isinstance(value, str):
            raise self._wrong(key, "a string")
        return value

    def optional_text(self, key: str) -> str | None:
        return None if self.record.get(key) is None else self.text(key)

    def hex_bytes(self, key: str) -> bytes:
        value = self.record.get(key)
        try:
            if not isinstance(value, str):
                raise ValueError
            return bytes.fromhex(value)
        except ValueError:
            raise self._wrong(key, "bytes in hex (an even number of 0-9, a-f)") from None

    def fields(self) -> dict[str, Any]:
        value = self.record.get("fields", {})
        if not isinstance(value, dict):
            raise self._wrong("fields", "an object of named fields")
        return value
