"""What the radio subcommands share: opening the radio, session, log writer and console model."""

from __future__ import annotations

import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

from particlebot.console.model import ConsoleModel
from particlebot.logs.jsonl import JsonlWriter, default_log_path
from particlebot.radio import Radio, open_radio
from particlebot.session import Session


@dataclass
class Station:
    """A running base station: radio, receive thread, log and console model."""

    radio: Radio
    session: Session
    model: ConsoleModel
    log: JsonlWriter | None

    @property
    def log_path(self) -> Path | None:
        return None if self.log is None else self.log.path


def has_terminal() -> bool:
    """Whether a person sits at this process: keys can come in and a screen can be drawn."""
    return sys.stdin.isatty() and sys.stdout.isatty()


def fail(message: str) -> int:
    print(f"particlebot: {message}", file=sys.stderr)
    return 2


def open_station(radio: Radio | str, log_dir: Path | None, *, fsync: bool = False) -> Station:
    """Opens the radio (RadioError on failure), starts logging (unless log_dir is None) and the
    receive thread."""
    radio = open_radio(radio) if isinstance(radio, str) else radio
    try:
        session = Session(radio)
        log = None
        if log_dir is not None:
            log = JsonlWriter(
                default_log_path(log_dir), radio=radio.url, fsync=fsync, clock=radio.now
            )
            session.add_listener(log)
        model = ConsoleModel(session, radio.now, quiet_hint=radio.quiet_hint)
        session.add_listener(model)
    except BaseException:
        radio.close()
        raise
    session.start()
    return Station(radio, session, model, log)


@contextmanager
def station(radio: Radio | str, log_dir: Path | None, *, fsync: bool = False) -> Iterator[Station]:
    opened = open_station(radio, log_dir, fsync=fsync)
    try:
        yield opened
    finally:
        opened.session.close()
        if opened.log_path is not None:
            print(f"Log: {opened.log_path}")


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """`kill` ends a headless session the way Ctrl-C does: cleanly, log closed."""

    def handler(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run_headless(
    model: ConsoleModel,
    until: Callable[[], int | None],
    *,
    report: Callable[[], None] | None = None,
    report_every_s: float = 10.0,
) -> int:
    """Polls the model until until() gives an exit code; report() every report_every_s."""
    next_report = time.monotonic() + report_every_s
    while True:
        model.poll()
        code = until()
        if code is not None:
            return code
        if report is not None and time.monotonic() >= next_report:
            report()
            next_report = time.monotonic() + report_every_s
        time.sleep(0.05)
