"""JSON-lines session log: one object per line, each written and flushed as it happens."""

from __future__ import annotations

import dataclasses
import datetime
import json
import os
import threading
import time
from collections.abc import Hashable, Iterator
from pathlib import Path
from typing import Any, cast

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

    def __init__(self, path: Path, *, radio: str = "", fsync: bool = False) -> None:
        self.path = path
        self.fsync = fsync
        self.lines = 0
        self._lock = threading.Lock()
        path.parent.mkdir(parents=True, exist_ok=True)
        self._fd: int | None = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
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
        line = {"t": round(time.time() if at is None else at, 6), **record}
        data = (json.dumps(line, separators=(",", ":")) + "\n").encode()
        with self._lock:
            if self._fd is None:
                return
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
        self.write({"kind": "end", "lines": self.lines + 1})
        with self._lock:
            fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)


class LogFormatError(ValueError):
    pass


def read_log(path: Path) -> Iterator[Record]:
    """Records of a log in order. A torn last line (power cut without fsync) is skipped; a bad
    line anywhere else raises LogFormatError naming it."""
    with path.open("rb") as file:
        lines = file.read().split(b"\n")
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
        yield record
