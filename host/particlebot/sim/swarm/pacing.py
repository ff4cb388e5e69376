"""Steps a simulation on its own thread, `speed` times faster than the wall clock (or flat out)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

LEAD_S = 0.05
"""Flat out, each round of stepping aims this far past the simulated present."""
MAX_LAG_S = 0.25
"""Behind the wall clock by more than this, the pace restarts from here: catching up would run
the simulation in bursts that a console would see as frozen, then racing, particles."""
BATCH_S = 0.1
"""Longest stretch of wall time spent stepping before stop() is looked at again."""


class PacedRunner:
    """Calls advance(target) on a thread until the simulated clock() reaches each target.

    advance(target) moves the simulation at most one small step towards target and returns
    False when it is already as close as its steps allow; clock() is the simulated time in
    seconds. step_s is about how much simulated time one call covers (it sets how long the
    thread naps between rounds). What advance raises ends the thread and is kept in `error`.
    """

    def __init__(
        self,
        clock: Callable[[], float],
        advance: Callable[[float], bool],
        *,
        name: str,
        step_s: float,
        join_timeout_s: float = 5.0,
    ) -> None:
        self.clock = clock
        self.advance = advance
        self.name = name
        self.step_s = step_s
        self.join_timeout_s = join_timeout_s
        self.speed = 1.0
        self.wall_origin = time.time() - clock()
        """The Unix time simulated time zero stands for; moved at start() so that simulated
        time read as wall time is now."""
        self.achieved_speed = 0.0
        """Simulated seconds per wall second since start()."""
        self.error: BaseException | None = None
        self._thread: threading.Thread | None = None
        self._running = threading.Event()

    def epoch(self, sim_s: float | None = None) -> float:
        """Simulated time sim_s (default now) as seconds since the Unix epoch."""
        return self.wall_origin + (self.clock() if sim_s is None else sim_s)

    def start(self, speed: float = 1.0) -> None:
        """Starts the thread (once; a second call while it runs changes nothing)."""
        if speed <= 0:
            raise ValueError("speed must be positive (math.inf: as fast as possible)")
        if self._thread is not None:
            return
        self.speed = speed
        self.wall_origin = time.time() - self.clock()
        self.error = None
        self._running.set()
        self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Ends the thread after its current step; safe from the thread itself."""
        self._running.clear()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=self.join_timeout_s)
        self._thread = None

    def _run(self) -> None:
        flat_out = math.isinf(self.speed)
        # A short nap lets other threads (the console, a radio) run; at high speed the nap must
        # not be longer than the simulated step it paces, or the pace would be missed.
        nap = 0.0 if flat_out else max(0.0005, min(0.005, self.step_s / self.speed))
        wall_start = measured_wall = time.monotonic()
        sim_start = measured_sim = self.clock()
        try:
            while self._running.is_set():
                now = time.monotonic()
                present = self.clock()
                if flat_out:
                    target = present + LEAD_S
                else:
                    target = sim_start + (now - wall_start) * self.speed
                    if target - present > MAX_LAG_S:
                        sim_start, wall_start = present, now
                        target = present + LEAD_S
                batch_end = time.monotonic() + BATCH_S
                while self._running.is_set() and self.advance(target):
                    if time.monotonic() > batch_end:
                        break
                elapsed = time.monotonic() - measured_wall
                if elapsed > 0:
                    self.achieved_speed = (self.clock() - measured_sim) / elapsed
                time.sleep(nap)
        except BaseException as exc:  # kept for the owner to report; the thread just ends
            self.error = exc
            self._running.clear()


class Paced:
    """The thread controls of a simulation that a PacedRunner (in `_runner`) steps."""

    _runner: PacedRunner

    @property
    def speed(self) -> float:
        return self._runner.speed

    @property
    def achieved_speed(self) -> float:
        """Simulated seconds per wall second the stepping thread has managed."""
        return self._runner.achieved_speed

    @property
    def error(self) -> BaseException | None:
        """What stopped the stepping thread, if something did."""
        return self._runner.error

    def start(self, speed: float = 1.0) -> None:
        """Steps on a thread, `speed` times faster than real time (math.inf: flat out)."""
        self._runner.start(speed)

    def stop(self) -> None:
        self._runner.stop()
