"""How many threads a large swarm's step runs on, chosen from the step times the machine gives
now: numba's parallel passes wait at every barrier for their slowest thread, so on a machine
where another process holds a core, two threads can run many times slower than one.

A world's results do not depend on its thread count (kernels.py: fixed chunks, no atomics), so
the choice can change between any two compiled calls without changing a bit of the run.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from statistics import median

SAMPLES = 3
"""Measurements kept per candidate: the median of the last three rides out one slow call."""
EXPLORE_EVERY_S = 20.0
"""Wall seconds between trying the candidate not in use again: load comes and goes, and a try
costs one compiled call (a quarter second in a simulate run) every 20 s, about 1 %."""
MARGIN = 1.1
"""More threads are kept only when they are at least this much faster per step: one thread
leaves a core to the rest of the machine, and a tie is not worth it."""
CLEARLY_WORSE = 2.0
"""A candidate this many times slower per step than the other after one measurement gets no
more at the start: on a busy machine a parallel step can be a hundred times slower, and each
more try of it costs that."""
TRIAL_S = 0.05
"""A try of the candidate not in use runs only as many steps as the one in use does in this
much wall time (at least one), so a try that stalls costs one short call, not a whole chunk."""


class ThreadGovernor:
    """Picks, before each compiled call of a parallel step, between one thread and `most`.

    Each candidate is measured (seconds per step, the median of its last SAMPLES calls) in turn
    at the start; from then on the faster is used, and the other is tried again for one call
    every EXPLORE_EVERY_S. The first call of a world is not measured (it builds lists, and may
    load kernels from numba's cache). The clock is injectable for tests.
    """

    def __init__(
        self,
        most: int,
        clock: Callable[[], float] = time.perf_counter,
        explore_every_s: float = EXPLORE_EVERY_S,
    ) -> None:
        self.candidates = (most, 1) if most > 1 else (1,)
        self.clock = clock
        self.explore_every_s = explore_every_s
        self._times: dict[int, deque[float]] = {c: deque(maxlen=SAMPLES) for c in self.candidates}
        self._calls = 0
        self._explored_at = clock()
        self._trial = False

    def per_step_s(self, threads: int) -> float | None:
        """The median seconds per step measured for `threads`, or None before any."""
        times = self._times.get(threads)
        return median(times) if times else None

    def best(self) -> int:
        """The faster candidate by the measurements so far (more threads only by MARGIN)."""
        most, *rest = self.candidates
        if not rest:
            return most
        many, one = self.per_step_s(most), self.per_step_s(1)
        if many is None or one is None:
            return most
        return most if many * MARGIN <= one else 1

    def choose(self) -> int:
        """The thread count for the next call."""
        self._trial = False
        short = [c for c in self.candidates if len(self._times[c]) < SAMPLES]
        if short and not self._settled():
            # The start: take turns, so that both candidates see the same stretch of the run.
            pick = short[self._calls % len(short)]
            self._trial = pick != self.best() or not self._times[pick]
            return pick
        best = self.best()
        if len(self.candidates) > 1 and self.clock() - self._explored_at >= self.explore_every_s:
            self._explored_at = self.clock()
            self._trial = True
            return next(c for c in self.candidates if c != best)
        return best

    def _settled(self) -> bool:
        """Whether the start can end early: one candidate clearly worse than the other."""
        measured = [self.per_step_s(c) for c in self.candidates]
        if len(measured) < 2 or any(m is None for m in measured):
            return len(measured) < 2
        fast, slow = sorted(m for m in measured if m is not None)
        return slow > CLEARLY_WORSE * fast

    def steps_cap(self) -> int | None:
        """At most this many steps in the call choose() just chose (a try), or None."""
        if not self._trial:
            return None
        known = [t for t in (self.per_step_s(c) for c in self.candidates) if t is not None]
        if not known:
            return 1
        return max(1, int(TRIAL_S / min(known)))

    def record(self, threads: int, steps: int, seconds: float) -> None:
        """A compiled call on `threads` took `seconds` for `steps` steps."""
        self._calls += 1
        if self._calls == 1 or steps <= 0 or threads not in self._times:
            return
        self._times[threads].append(seconds / steps)
