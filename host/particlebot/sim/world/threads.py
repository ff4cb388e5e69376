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
        self._exploring: int | None = None

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
        self._exploring = None
        for candidate in self.candidates:
            if len(self._times[candidate]) < SAMPLES:
                return self._alternate()
        best = self.best()
        if self.clock() - self._explored_at >= self.explore_every_s:
            self._explored_at = self.clock()
            other = next(c for c in self.candidates if c != best)
            self._exploring = other
            return other
        return best

    def _alternate(self) -> int:
        # The start: take turns, so that both candidates see the same stretch of the run.
        short = [c for c in self.candidates if len(self._times[c]) < SAMPLES]
        return short[self._calls % len(short)]

    def record(self, threads: int, steps: int, seconds: float) -> None:
        """A compiled call on `threads` took `seconds` for `steps` steps."""
        self._calls += 1
        if self._calls == 1 or steps <= 0 or threads not in self._times:
            return
        self._times[threads].append(seconds / steps)
