"""A study's progress line: runs done of all, failures, the share of the work done (runs still
going count by how far they are), elapsed time and an ETA weighted by cost."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TextIO

from particlebot.progress import ProgressLine, bar_text, clock_text


class Progress(ProgressLine):
    """Counts runs and estimates the time left from their cost (particle-steps), not their number:
    a study mixes runs of 10 and 10,000 particles, and starts the dear ones first. A run that is
    still going counts by the share of its steps it reported (running()), so a study of a few long
    runs has an ETA before the first one ends.

    On a terminal it redraws one line, every second while runs are out; otherwise (a log, a
    batch job) it prints a line every report_every_s seconds, and always the last
    (particlebot.progress decides when).
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
        super().__init__(stream, clock, report_every_s)
        self.label = label
        self.total = total
        self.done = done
        self.failed = 0
        self.cost_left = cost_left
        self.cost_done = 0.0
        self.cost_total = cost_left
        self.in_flight: dict[str, tuple[float, float, float]] = {}
        """run id -> (its cost, the share done when this invocation first heard of it, the share
        done now): a resumed run's earlier share is neither work done now nor work left."""
        self.ended: set[str] = set()
        self.last_news = self.started
        """When the work done last changed (a report or a result)."""

    def complete(self) -> bool:
        return self.done == self.total

    def running(self, run_id: str, cost: float, share_at_start: float, share_now: float) -> None:
        """A run that is going reported how far it is (shares of its steps, 0 to 1)."""
        with self._lock:
            if run_id in self.ended:
                return  # a report that crossed the result on its way
            first = self.in_flight.get(run_id, (cost, share_at_start, share_now))[1]
            self.in_flight[run_id] = (cost, first, min(1.0, max(share_now, first)))
            self.last_news = self.clock()

    def advance(self, cost: float, failed: bool = False, run_id: str | None = None) -> None:
        """One run came back (finished, or failed for good)."""
        with self._lock:
            if run_id is not None:
                self.ended.add(run_id)
                self.in_flight.pop(run_id, None)
            self.done += 1
            self.last_news = self.clock()
            self.failed += failed
            self.cost_done += cost
            self.cost_left = max(0.0, self.cost_left - cost)
        self.show()

    def _work(self) -> tuple[float, float]:
        """(cost done by this invocation, cost left), runs in flight counted by their share."""
        done, left = self.cost_done, self.cost_left
        for cost, first, now in self.in_flight.values():
            done += cost * (now - first)
            left -= cost * now
        return done, max(0.0, left)

    def eta_s(self) -> float | None:
        """The time left at the pace measured up to the last news, counting down since: between
        reports it falls steadily instead of growing and then dropping."""
        done, left = self._work()
        if done <= 0:
            return None
        at_news = (self.last_news - self.started) * left / done
        return max(0.0, at_news - (self.clock() - self.last_news))

    def share_done(self) -> float:
        """The share of this invocation's work that is done, 0 to 1."""
        if self.cost_total <= 0:
            return 1.0
        return 1.0 - self._work()[1] / self.cost_total

    def line(self) -> str:
        share = self.share_done()
        eta = self.eta_s()
        parts = [
            f"{self.label}: {self.done}/{self.total} runs",
            f"{bar_text(share)} {100 * share:3.0f} %",
        ]
        if self.failed:
            parts.append(f"{self.failed} failed")
        parts.append(f"elapsed {clock_text(self.clock() - self.started)}")
        parts.append("ETA " + ("--" if eta is None else clock_text(eta)))
        return "  ".join(parts)
