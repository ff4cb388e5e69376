"""What the radio subcommands share: a Swarm opened for the command line, headless loops."""

from __future__ import annotations

import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

from particlebot.fleet import Fleet
from particlebot.radio import Radio
from particlebot.swarm.api import Swarm


def has_terminal() -> bool:
    """Whether a person sits at this process: keys can come in and a screen can be drawn."""
    return sys.stdin.isatty() and sys.stdout.isatty()


def fail(message: str) -> int:
    print(f"particlebot: {message}", file=sys.stderr)
    return 2


@contextmanager
def opened_swarm(
    radio: Radio | str,
    log_dir: Path | None,
    *,
    fsync: bool = False,
    fleet: Fleet | Path | None = None,
    stepped: bool | None = None,
    announce_log: bool = True,
) -> Iterator[Swarm]:
    """Swarm.open (RadioError, LogError or FleetFileError on failure); closed on the way out,
    and the log's path printed, so a person always learns where the session went (unless
    announce_log is False: a scratch log nobody keeps)."""
    swarm = Swarm.open(radio, log_dir=log_dir, fsync=fsync, fleet=fleet, stepped=stepped)
    try:
        yield swarm
    finally:
        swarm.close()
        if swarm.log_path is not None and announce_log:
            print(f"Log: {swarm.log_path}")


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
    swarm: Swarm,
    until: Callable[[], int | None],
    *,
    report: Callable[[], None] | None = None,
    report_every_s: float = 10.0,
) -> int:
    """Polls the swarm until until() gives an exit code; report() every report_every_s of wall
    time. A simulation stepped by the swarm runs as fast as it can meanwhile."""
    next_report = time.monotonic() + report_every_s
    while True:
        swarm.poll()
        code = until()
        if code is not None:
            return code
        if report is not None and time.monotonic() >= next_report:
            report()
            next_report = time.monotonic() + report_every_s
        if not swarm.stepped:
            time.sleep(swarm.poll_wall_s)
