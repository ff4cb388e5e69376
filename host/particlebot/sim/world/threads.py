"""How many threads a large swarm's step runs on, chosen from the step times the machine gives
now: numba's parallel passes wait at every barrier for their slowest thread, so on a machine
where another process holds a core, two threads can run many times slower than one.

A world's results do not depend on its thread count (kernels.py: fixed chunks, no atomics), so
the choice can change between any two compiled calls without changing a bit of the run.

Each estimate is the throughput of the last several seconds of that count's calls (older calls
weigh less the older they are), not of a number of calls: a controller may hand the world a few
steps at a time (calls of 3 ms), and on a shared machine the time a parallel step takes wanders
by a factor of two or more from one second to the next, so a few calls or a fraction of a second
say little about which count is faster.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

MEMORY_S = 10.0
"""Wall seconds over which a count's estimate forgets: a call this much older than the latest
weighs 1/e as much. Long enough to average a shared machine's wandering, short enough to follow
load that comes and goes."""
WINDOW_S = 0.5
"""Wall seconds of calls the count in use has measured before the other is tried at all."""
TRIAL_S = 0.5
"""Wall seconds a try of the other count measures before it is judged."""
TRIAL_CALL_S = 0.05
"""A call during a try runs only as many steps as the count in use does in this much wall time
(at least one), so a count that stalls costs short calls, not a whole chunk."""
CLOSE_EXPLORE_S = 4.0
"""Wall seconds between tries when the other count was within CLEARLY_WORSE of the one in use:
trying a close rival costs little, and each try adds to its estimate."""
EXPLORE_EVERY_S = 20.0
"""Wall seconds between tries of a count that was CLEARLY_WORSE: load comes and goes, and such a
try (ended after TRIAL_CALL_S of the count in use's steps) every 20 s costs about 2 % of a run."""
RECHECK_AFTER_S = 2.0
"""When the count in use falls behind the other's estimate (load arrived), the other is tried
again at once, but not sooner than this after the last try."""
MARGIN = 1.1
"""More threads are kept only when they are at least this much faster per step: one thread
leaves a core to the rest of the machine, and a tie is not worth it."""
CLEARLY_WORSE = 2.0
"""A try ends early, after TRIAL_CALL_S of it, when the count tried is this many times slower
per step than the count in use: on a busy machine a parallel step can be a hundred times
slower, and each more call of it costs that."""


class _Estimate:
    """The steps and seconds of one thread count's calls, each weighted by exp(-age/MEMORY_S)."""

    def __init__(self) -> None:
        self.steps = 0.0
        self.seconds = 0.0
        self.measured_s = 0.0
        """Unweighted seconds measured since the estimate began (or was last cleared)."""
        self._at: float | None = None

    def add(self, steps: int, seconds: float, now: float) -> None:
        if self._at is not None:
            fade = math.exp(-max(now - self._at, 0.0) / MEMORY_S)
            self.steps *= fade
            self.seconds *= fade
        self._at = now
        self.steps += steps
        self.seconds += seconds
        self.measured_s += seconds

    def restart(self) -> None:
        """Counts measured time afresh (a new try) and keeps what is known, faded."""
        self.measured_s = 0.0

    def per_step_s(self) -> float | None:
        return self.seconds / self.steps if self.steps else None


class ThreadGovernor:
    """Picks, before each compiled call of a parallel step, between one thread and `most`.

    It starts on `most`; once WINDOW_S of calls are measured it tries the other count for
    TRIAL_S (ended early if that count is CLEARLY_WORSE), and then runs on the faster by their
    estimates, trying the other again every CLOSE_EXPLORE_S (a close rival) or EXPLORE_EVERY_S
    (a clearly worse one), or RECHECK_AFTER_S after a try when the count in use has fallen
    behind. The first call of a world is not measured (it builds lists, and may load kernels
    from numba's cache). The clock is injectable for tests.
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
        self._estimates = {c: _Estimate() for c in self.candidates}
        self._current = self.candidates[0]
        self._trying: int | None = None
        self._tried_at: float | None = None
        self._calls = 0

    @property
    def trying(self) -> int | None:
        """The count under trial, or None while the count in use runs."""
        return self._trying

    def per_step_s(self, threads: int) -> float | None:
        """Seconds per step estimated for `threads`, or None before any call of it."""
        estimate = self._estimates.get(threads)
        return estimate.per_step_s() if estimate else None

    def best(self) -> int:
        """The faster candidate by the measurements so far (more threads only by MARGIN)."""
        most, *rest = self.candidates
        if not rest:
            return most
        many, one = self.per_step_s(most), self.per_step_s(1)
        if many is None or one is None:
            return self._current
        return most if many * MARGIN <= one else 1

    def choose(self) -> int:
        """The thread count for the next call."""
        if self._trying is not None or len(self.candidates) == 1:
            return self._trying or self._current
        if self._estimates[self._current].measured_s < WINDOW_S:
            return self._current  # not enough known about the count in use to compare yet
        other = next(c for c in self.candidates if c != self._current)
        now = self.clock()
        since = None if self._tried_at is None else now - self._tried_at
        if (
            since is None
            or since >= self._explore_gap(other)
            or (since >= RECHECK_AFTER_S and self.best() != self._current)
        ):
            self._trying = other
            self._tried_at = now
            self._estimates[other].restart()
            return other
        return self._current

    def _explore_gap(self, other: int) -> float:
        """Wall seconds between tries of `other`: short for a close rival, long for a count that
        was clearly worse."""
        theirs, ours = self.per_step_s(other), self.per_step_s(self._current)
        if theirs is not None and ours is not None and theirs > CLEARLY_WORSE * ours:
            return self.explore_every_s
        return min(CLOSE_EXPLORE_S, self.explore_every_s)

    def steps_cap(self) -> int | None:
        """At most this many steps in the call choose() just chose (a try), or None."""
        if self._trying is None:
            return None
        known = self.per_step_s(self._current)
        return 1 if known is None else max(1, int(TRIAL_CALL_S / known))

    def record(self, threads: int, steps: int, seconds: float) -> None:
        """A compiled call on `threads` took `seconds` for `steps` steps."""
        self._calls += 1
        if self._calls == 1 or steps <= 0 or threads not in self._estimates:
            return
        estimate = self._estimates[threads]
        estimate.add(steps, seconds, self.clock())
        if threads != self._trying:
            return
        # A stall is judged on this try's own calls, not on the faded estimate it joins.
        tried, in_use = seconds / steps, self.per_step_s(self._current)
        stalls = (
            estimate.measured_s >= TRIAL_CALL_S
            and tried is not None
            and in_use is not None
            and tried > CLEARLY_WORSE * in_use
        )
        if estimate.measured_s >= TRIAL_S or stalls:
            self._trying = None
            chosen = self.best()
            if chosen != self._current:
                self._current = chosen
                self._estimates[self._current].restart()  # WINDOW_S more before a try
