"""The world's thread choice: the faster of one thread and all, as measured, tried again as the
load changes; an explicit count is kept; and the choice never changes a bit of the run."""

from __future__ import annotations

import hashlib

import numba
import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import hexagonal
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world import world as world_module
from particlebot.sim.world.threads import (
    CLOSE_EXPLORE_S,
    EXPLORE_EVERY_S,
    TRIAL_CALL_S,
    TRIAL_S,
    WINDOW_S,
    ThreadGovernor,
)


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class Run:
    """Compiled calls driven through a governor on a fake clock: each takes the wall time its
    per-step cost says; what was chosen, and how much wall time each count had."""

    def __init__(self, governor: ThreadGovernor, clock: FakeClock) -> None:
        self.governor, self.clock = governor, clock
        self.chosen: list[int] = []
        self.began: list[float] = []

    def drive(self, per_step: dict[int, float], calls: int, steps: int = 100) -> Run:
        for _ in range(calls):
            threads = self.governor.choose()
            rows = min(steps, self.governor.steps_cap() or steps)
            self.chosen.append(threads)
            self.began.append(self.clock.now)
            self.governor.record(threads, rows, rows * per_step[threads])
            self.clock.now += rows * per_step[threads]
        return self

    def seconds_on(self, threads: int, since: float = 0.0) -> float:
        ends = [*self.began[1:], self.clock.now]
        return sum(
            end - max(start, since)
            for start, end, chosen in zip(self.began, ends, self.chosen, strict=True)
            if chosen == threads and end > since
        )


IDLE = {2: 0.6e-3, 1: 1.0e-3}  # two threads do a step in 60 % of one thread's time
BUSY = {2: 9.0e-3, 1: 1.0e-3}  # another process holds a core: the parallel passes wait for it


def test_the_count_in_use_is_measured_then_the_other_tried_and_the_faster_kept() -> None:
    clock = FakeClock()
    run = Run(ThreadGovernor(2, clock=clock), clock).drive(IDLE, calls=1000)  # 60 s
    first_try = run.chosen.index(1)
    # The try comes once the count in use has WINDOW_S measured (the first call is not).
    assert run.began[first_try] >= WINDOW_S
    # Then two threads, but for tries of the close rival: TRIAL_S every CLOSE_EXPLORE_S.
    assert run.chosen[-1] == 2
    share = run.seconds_on(1) / clock.now
    assert 0.0 < share <= 1.2 * TRIAL_S / CLOSE_EXPLORE_S


def test_a_busy_machine_falls_back_to_one_thread_and_returns_when_it_is_idle_again() -> None:
    clock = FakeClock()
    run = Run(ThreadGovernor(2, clock=clock), clock).drive(BUSY, calls=300)  # 30 s
    # One thread all but the stalled count's short tries: each one call, every 20 s.
    assert run.seconds_on(2, since=5.0) <= 2 * 9 * TRIAL_CALL_S
    idle_from = clock.now
    run.drive(IDLE, calls=1000)
    # Tried again within 20 s, two threads win their try and keep the run.
    back = next(t for t, c in zip(run.began, run.chosen, strict=True) if t > idle_from and c == 2)
    assert back - idle_from <= EXPLORE_EVERY_S
    assert run.seconds_on(1, since=back + TRIAL_S) / (clock.now - back) <= 0.15


def test_a_few_slow_calls_do_not_switch_the_count() -> None:
    # A controller that hands the world six steps at a time makes calls of a few milliseconds;
    # three of them descheduled (ten times slower) must not move an idle run to one thread.
    hiccup = {2: 10 * IDLE[2], 1: IDLE[1]}
    clocks = FakeClock(), FakeClock()
    calm, bumped = (Run(ThreadGovernor(2, clock=c), c) for c in clocks)
    calm.drive(IDLE, calls=5000, steps=6).drive(IDLE, calls=5000, steps=6)
    bumped.drive(IDLE, calls=5000, steps=6).drive(hiccup, calls=3, steps=6)
    bumped.drive(IDLE, calls=5000, steps=6)
    # At most one more try of one thread than without the hiccup.
    assert bumped.seconds_on(1) - calm.seconds_on(1) <= TRIAL_S + 6 * IDLE[1]
    assert bumped.chosen[-1] == 2


def test_load_that_arrives_is_followed_within_seconds() -> None:
    clock = FakeClock()
    run = Run(ThreadGovernor(2, clock=clock), clock).drive(IDLE, calls=500)
    busy_from = clock.now
    run.drive(BUSY, calls=300)
    # Two threads stall for seconds (their estimate fades towards the new load, and the recheck
    # tries one thread), not for the 20 s of the exploring period; then only short tries.
    assert run.seconds_on(2, since=busy_from) <= 8.0
    assert run.chosen[-1] == 1


def test_a_count_that_stalls_is_tried_in_short_calls_and_dropped_after_one() -> None:
    clock = FakeClock()
    governor = ThreadGovernor(2, clock=clock)
    Run(governor, clock).drive({1: 1.0e-3, 2: 1.0e-3}, calls=40)  # a tie: one thread runs
    assert governor.choose() == 1 and governor.steps_cap() is None
    clock.now += CLOSE_EXPLORE_S
    assert governor.choose() == 2 and governor.trying == 2
    cap = governor.steps_cap()
    assert cap is not None  # a try's call: 0.05 s of the in-use count's steps (the estimate's
    assert abs(cap - TRIAL_CALL_S / 1.0e-3) <= 1  # fading may round it down by one)
    governor.record(2, cap, cap * 0.15)  # 150 times slower: the try ends after that one call
    assert governor.trying is None
    assert [governor.choose() for _ in range(5)] == [1] * 5


def test_a_tie_leaves_the_other_cores_to_the_machine() -> None:
    clock = FakeClock()
    run = Run(ThreadGovernor(2, clock=clock), clock).drive({2: 0.95e-3, 1: 1.0e-3}, calls=400)
    assert run.chosen[-1] == 1
    assert run.seconds_on(2, since=5.0) / (clock.now - 5.0) <= 0.15


def test_one_core_has_nothing_to_choose() -> None:
    governor = ThreadGovernor(1)
    assert governor.choose() == 1 and governor.candidates == (1,)


def _digest(world: World) -> str:
    state = world.state()
    digest = hashlib.sha256()
    for row in (state.x, state.y, state.vx, state.vy, world.radii()):
        digest.update(np.ascontiguousarray(row).tobytes())
    return digest.hexdigest()


def _packed(threads: int | None) -> World:
    blob = hexagonal(world_module.PARALLEL_FROM + 200, 2 * PhysicsParams().r_min)
    world = World(blob.xy[:, 0], blob.xy[:, 1], controller=PublishedController(),
                  lamp=Lamp(-30.0, 0.0), seed=3)  # fmt: skip
    world.thread_count = threads
    for _ in range(12):
        world.step(5)  # many compiled calls: the governor switches between them
    return world


def test_the_choice_changes_no_bit_and_an_explicit_count_is_kept() -> None:
    most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    one = _packed(1)
    assert one.threads == 1
    chosen = _packed(None)
    assert chosen._governor is not None  # measured, not fixed
    assert _digest(chosen) == _digest(one)
    if most > 1:
        every = _packed(most)
        assert every.threads == most and every._governor is None
        assert _digest(every) == _digest(one)
