"""A study's progress line: runs done of all, failures, elapsed time and an ETA weighted by cost."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import TextIO


def clock_text(seconds: float) -> str:
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}"


class Progress:
    """Counts runs and estimates the time left from their cost (particle-steps), not their number:
    a study mixes runs of 10 and 10,000 particles, and starts the dear ones first.

    On a terminal it redraws one line, every second while runs are out; otherwise (a log, a
    batch job) it prints a line every report_every_s seconds, and always the last.
    """

    def __init__(
        self,
        label: str,
        total: int,
        done: int,
        cost_left: float,
        stream: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
        report_every_s: float = 30.0,
    ) -> None:
        self.label = label
        self.total = total
        self.done = done
        self.failed = 0
        self.cost_left = cost_left
        self.cost_done = 0.0
        self.stream = stream if stream is not None else sys.stderr
        self.clock = clock
        self.started = clock()
        self.report_every_s = report_every_s
        self.last_report = -float("inf")
        self.live = self.stream.isatty()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    def start(self) -> None:
        """Shows the line now and keeps the clock on it moving between runs."""
        self.show(force=True)
        self._ticker = threading.Thread(target=self._tick, name="study-progress", daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(1.0 if self.live else self.report_every_s):
            self.show()

    def advance(self, cost: float, failed: bool = False) -> None:
        """One run came back (finished, or failed for good)."""
        with self._lock:
            self.done += 1
            self.failed += failed
            self.cost_done += cost
            self.cost_left = max(0.0, self.cost_left - cost)
        self.show()

    def eta_s(self) -> float | None:
        if self.cost_done <= 0:
            return None
        return (self.clock() - self.started) * self.cost_left / self.cost_done

    def line(self) -> str:
        width = 24
        filled = width * self.done // self.total if self.total else width
        eta = self.eta_s()
        parts = [
            f"{self.label}: {self.done}/{self.total} runs",
            f"[{'#' * filled}{'.' * (width - filled)}]",
        ]
        if self.failed:
            parts.append(f"{self.failed} failed")
        parts.append(f"elapsed {clock_text(self.clock() - self.started)}")
        parts.append("ETA " + ("--" if eta is None else clock_text(eta)))
        return "  ".join(parts)

    def show(self, force: bool = False) -> None:
        with self._lock:
            now = self.clock()
            if self.live:
                self.stream.write("\r" + self.line() + "\x1b[K")
            elif force or self.done == self.total or now - self.last_report >= self.report_every_s:
                self.stream.write(self.line() + "\n")
                self.last_report = now
            self.stream.flush()

    def close(self) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        if self.live:
            with self._lock:
                self.stream.write("\n")
                self.stream.flush()
