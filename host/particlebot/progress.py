"""Progress of long jobs on stderr, the one module that prints it: a line redrawn in place on a
terminal, a line every few seconds of wall time otherwise (CI logs and redirected output stay
readable), with the elapsed time and an ETA from the wall-clock rate of the work itself."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from types import TracebackType
from typing import TextIO

REPORT_EVERY_S = 5.0
"""Without a terminal, a line at least this often (of wall time) while the work goes on."""
REDRAW_EVERY_S = 0.2
"""On a terminal, redraws no more often than this (a redraw costs a write per call otherwise)."""
WIDTH = 24
"""Characters of the bar."""


def clock_text(seconds: float) -> str:
    """h:mm:ss."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}"


def bar_text(share: float) -> str:
    """[#####.......] for a share of 0 to 1."""
    filled = min(WIDTH, max(0, int(WIDTH * share)))
    return f"[{'#' * filled}{'.' * (WIDTH - filled)}]"


class ProgressLine:
    """When a progress line shows; what it says is line(), which subclasses give.

    show() is called whenever there is news; start() also keeps a ticker thread that calls it
    every second (terminal) or interval (log), so that the elapsed time moves and a log gets its
    line while nothing reports (a compile, an encoder running). The clock is injectable for tests.
    """

    def __init__(
        self,
        stream: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
        report_every_s: float = REPORT_EVERY_S,
        live: bool | None = None,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.clock = clock
        self.report_every_s = report_every_s
        self.live = self.stream.isatty() if live is None else live
        self.started = clock()
        self.last_report = -float("inf")
        self._last_line = ""
        self._shown_complete = False
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    def line(self) -> str:
        raise NotImplementedError

    def complete(self) -> bool:
        """Whether the work is all done (its line always shows)."""
        return False

    def show(self, force: bool = False) -> None:
        with self._lock:
            now = self.clock()
            if self.live:
                if force or self.complete() or now - self.last_report >= REDRAW_EVERY_S:
                    self._last_line = self.line()
                    self.stream.write("\r" + self._last_line + "\x1b[K")
                    self.last_report = now
            elif not self._shown_complete and (
                force or self.complete() or now - self.last_report >= self.report_every_s
            ):
                self._last_line = self.line()
                self.stream.write(self._last_line + "\n")
                self._shown_complete = self.complete()
                self.last_report = now
            self.stream.flush()

    def start(self, show_now: bool = True) -> None:
        """Shows the line now (unless not show_now) and keeps it moving until close()."""
        if show_now:
            self.show(force=True)
        self._ticker = threading.Thread(target=self._tick, name="progress", daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(1.0 if self.live else self.report_every_s):
            self.show()

    def close(self) -> None:
        """Stops the ticker and leaves the last line (on a terminal, ends it); once."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        with self._lock:
            if self.live:
                self.stream.write("\r" + self.line() + "\x1b[K\n")
            elif not self._shown_complete:
                self.stream.write(self.line() + "\n")  # where it stopped
            self.stream.flush()

    def __enter__(self) -> ProgressLine:
        self.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()


class ProgressBar(ProgressLine):
    """`label  42% [##########..............] 420/1000 frames, elapsed 0:00:12, ETA 0:00:16`.

    The ETA comes from the wall-clock rate measured since the first update: what happens before
    it (compiling kernels, opening a video) is not work the rest repeats. Between updates it
    counts down instead of standing still. With no total, the line counts."""

    def __init__(
        self,
        label: str,
        total: float,
        unit: str = "frames",
        stream: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
        report_every_s: float = REPORT_EVERY_S,
        live: bool | None = None,
        decimals: int = 0,
    ) -> None:
        super().__init__(stream, clock, report_every_s, live)
        self.label = label
        self.total = max(0.0, total)
        self.unit = unit
        self.decimals = decimals
        """Digits after the point of the amounts shown (a short run's simulated seconds)."""
        self.done = 0.0
        self.note = ""
        self._origin: tuple[float, float] | None = None
        """(time, done) of the first update: where the rate is measured from."""
        self._news = (self.started, 0.0)
        """(time, done) of the latest update."""

    def update(self, done: float, note: str = "") -> None:
        """`done` of the total so far, and a note after the line (a speed, say)."""
        with self._lock:
            now = self.clock()
            if self._origin is None:
                self._origin = (now, done)
            self.done = done
            self.note = note
            self._news = (now, done)
        self.show()

    def complete(self) -> bool:
        return self.total > 0 and self.done >= self.total

    def show(self, force: bool = False) -> None:
        if self._origin is None and not force:
            return  # the ticker waits for the work's first news (the first line says where it is)
        super().show(force)

    def eta_s(self) -> float | None:
        """Seconds left at the rate since the first update; None before there is a rate."""
        if self._origin is None or self.total <= 0:
            return None
        (t0, d0), (t1, d1) = self._origin, self._news
        if d1 <= d0 or t1 <= t0:
            return None
        at_news = (t1 - t0) * max(0.0, self.total - d1) / (d1 - d0)
        return max(0.0, at_news - (self.clock() - t1))

    def line(self) -> str:
        elapsed = clock_text(self.clock() - self.started)
        done = f"{self.done:.{self.decimals}f}"
        if self.total <= 0:
            text = f"{self.label}: {done} {self.unit}, elapsed {elapsed}"
        else:
            share = min(1.0, self.done / self.total)
            eta = self.eta_s()
            total = f"{self.total:.{self.decimals}f}"
            text = (
                f"{self.label} {100 * share:3.0f}% {bar_text(share)} {done}/{total} "
                f"{self.unit}, elapsed {elapsed}, ETA {'--' if eta is None else clock_text(eta)}"
            )
        return f"{text}, {self.note}" if self.note else text

    def finish(self) -> None:
        """close() under the name the commands call it by."""
        self.close()


class Activity(ProgressLine):
    """A job without a measure of how far it is (numba compiling, a file being written): its
    label and the time it has taken, and what it usually takes when that is known."""

    def __init__(
        self,
        label: str,
        usual_s: float | None = None,
        stream: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
        report_every_s: float = REPORT_EVERY_S,
        live: bool | None = None,
    ) -> None:
        super().__init__(stream, clock, report_every_s, live)
        self.label = label
        self.usual_s = usual_s

    def line(self) -> str:
        text = f"{self.label}: {clock_text(self.clock() - self.started)}"
        return text if self.usual_s is None else f"{text} (usually about {self.usual_s:.0f} s)"
