"""A progress bar for long jobs on stderr: redrawn in place on a terminal, a line every tenth
otherwise (so CI logs and redirected output stay readable)."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class ProgressBar:
    def __init__(
        self, label: str, total: int, unit: str = "frames", stream: TextIO | None = None
    ) -> None:
        self.label = label
        self.total = max(0, total)
        self.unit = unit
        self.stream = stream if stream is not None else sys.stderr
        self._live = self.stream.isatty()
        self._started = time.monotonic()
        self._last_draw = 0.0
        self._last_tenth = -1
        self._done = 0
        self._note = ""

    def _line(self, done: int) -> str:
        line = self._bar(done)
        return f"{line}, {self._note}" if self._note else line

    def _bar(self, done: int) -> str:
        elapsed = time.monotonic() - self._started
        if self.total <= 0:
            return f"{self.label}: {done} {self.unit}, {elapsed:.0f} s"
        fraction = min(1.0, done / self.total)
        filled = round(24 * fraction)
        left = elapsed / fraction - elapsed if fraction > 0 else 0.0
        return (
            f"{self.label} {100 * fraction:3.0f}% [{'#' * filled}{'.' * (24 - filled)}] "
            f"{done}/{self.total} {self.unit}, {left:.0f} s left"
        )

    def update(self, done: int, note: str = "") -> None:
        """Shows `done` of the total, and a note after it (e.g. a speed)."""
        self._done = done
        self._note = note
        now = time.monotonic()
        if self._live:
            if now - self._last_draw >= 0.2:
                self._last_draw = now
                self.stream.write("\r" + self._line(done) + "\033[K")
                self.stream.flush()
            return
        tenth = int(10 * done / self.total) if self.total > 0 else done // 1000
        if tenth > self._last_tenth:
            self._last_tenth = tenth
            self.stream.write(self._line(done) + "\n")
            self.stream.flush()

    def finish(self) -> None:
        if self._live:
            self.stream.write("\r" + self._line(self._done) + "\033[K\n")
            self.stream.flush()
