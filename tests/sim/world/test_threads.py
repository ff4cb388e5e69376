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
from particlebot.sim.world.threads import SAMPLES, ThreadGovernor


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def drive(
    governor: ThreadGovernor, clock: FakeClock, per_step: dict[int, float], calls: int
) -> list[int]:
    """`calls` calls of 100 steps, each 0.25 s of wall time apart; the counts chosen."""
    chosen = []
    for _ in range(calls):
        threads = governor.choose()
        chosen.append(threads)
        governor.record(threads, 100, 100 * per_step[threads])
        clock.now += 0.25
    return chosen


def test_both_counts_are_measured_in_turn_then_the_faster_is_kept() -> None:
    clock = FakeClock()
    governor = ThreadGovernor(2, clock=clock)
    # Idle machine: two threads do a step in 60 % of one thread's time.
    chosen = drive(governor, clock, {2: 0.6e-3, 1: 1.0e-3}, calls=1 + 2 * SAMPLES + 20)
    start = chosen[: 1 + 2 * SAMPLES]
    assert start.count(1) >= SAMPLES and start.count(2) >= SAMPLES
    assert set(chosen[1 + 2 * SAMPLES :]) == {2}


def test_a_busy_machine_falls_back_to_one_thread_and_returns_when_it_is_idle_again() -> None:
    clock = FakeClock()
    governor = ThreadGovernor(2, clock=clock, explore_every_s=20.0)
    # Another process holds a core: the parallel passes wait for it (9 times slower).
    busy = {2: 9.0e-3, 1: 1.0e-3}
    assert drive(governor, clock, busy, calls=40)[-10:] == [1] * 10
    idle = {2: 0.6e-3, 1: 1.0e-3}
    chosen = drive(governor, clock, idle, calls=400)  # 100 s of wall time
    # Tried again every 20 s, two threads win once their median is fresh, and stay.
    assert chosen[-10:] == [2] * 10
    # What the exploring cost: few calls on the slower count while busy, and few while idle.
    assert chosen.count(1) < 200


def test_a_count_that_stalls_is_tried_in_short_calls_and_dropped_after_one_measurement() -> None:
    clock = FakeClock()
    governor = ThreadGovernor(2, clock=clock, explore_every_s=20.0)
    assert governor.choose() == 2 and governor.steps_cap() == 1  # nothing known: one step
    governor.record(2, 1, 1.0)  # (a world's first call is not measured)
    assert governor.choose() == 1 and governor.steps_cap() == 1
    governor.record(1, 1, 1.0e-3)
    assert governor.choose() == 2
    governor.record(2, 1, 0.15)  # 150 times slower: no second try at the start
    assert [governor.choose() for _ in range(5)] == [1] * 5
    assert governor.steps_cap() is None  # the count in use runs whole chunks
    clock.now = 20.0
    assert governor.choose() == 2  # tried again after 20 s, for 0.05 s of the other's steps
    assert governor.steps_cap() == 50


def test_a_tie_leaves_the_other_cores_to_the_machine() -> None:
    clock = FakeClock()
    governor = ThreadGovernor(2, clock=clock)
    chosen = drive(governor, clock, {2: 0.95e-3, 1: 1.0e-3}, calls=20)
    assert chosen[-5:] == [1] * 5


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
