"""The wall-clock pacing thread both simulated swarms step on: pace, errors, stopping."""

from __future__ import annotations

import threading
import time

import pytest

from particlebot.sim.swarm.pacing import PacedRunner
from tests.support.fakes import wait_until

STEP_S = 0.005


class FakeSimulation:
    """A clock that advances STEP_S per step, noting the wall time of each step."""

    def __init__(self) -> None:
        self.t = 0.0
        self.steps: list[tuple[float, float]] = []
        self.reached = threading.Event()
        self.goal = float("inf")
        self.thread: threading.Thread | None = None

    def clock(self) -> float:
        return self.t

    def advance(self, target: float) -> bool:
        if self.t + STEP_S > target + 1e-9:
            return False
        self.t += STEP_S
        self.steps.append((time.monotonic(), self.t))
        self.thread = threading.current_thread()
        if self.t >= self.goal:
            self.reached.set()
        return True


def test_a_paced_simulation_never_runs_ahead_of_the_wall_clock_times_its_speed() -> None:
    sim = FakeSimulation()
    sim.goal = 0.5
    runner = PacedRunner(sim.clock, sim.advance, name="test-pacing", step_s=STEP_S)
    began = time.monotonic()
    runner.start(speed=10.0)
    try:
        assert sim.reached.wait(timeout=120)  # a hang guard (0.05 s idle)
    finally:
        runner.stop()
    # A step may only end where the wall clock, times the speed, has already got to.
    assert all(t <= (wall - began) * 10.0 + 1e-9 for wall, t in sim.steps)
    assert runner.achieved_speed > 0


def test_what_the_simulation_raises_ends_the_thread_and_is_kept() -> None:
    def advance(target: float) -> bool:
        raise RuntimeError("the harness died")

    runner = PacedRunner(lambda: 0.0, advance, name="test-pacing", step_s=STEP_S)
    runner.start()
    assert wait_until(lambda: runner.error is not None)
    assert isinstance(runner.error, RuntimeError)
    runner.stop()


def test_the_stepping_thread_may_stop_itself() -> None:
    sim = FakeSimulation()
    runners: list[PacedRunner] = []

    def advance_then_stop(target: float) -> bool:
        moved = sim.advance(target)
        if sim.t >= 0.05:
            runners[0].stop()  # e.g. a simulation that decides it is finished
        return moved

    runner = PacedRunner(sim.clock, advance_then_stop, name="test-pacing", step_s=STEP_S)
    runners.append(runner)
    runner.start(speed=float("inf"))
    assert wait_until(lambda: sim.thread is not None and sim.t >= 0.05)
    assert sim.thread is not None
    sim.thread.join(timeout=5)
    assert not sim.thread.is_alive()
    assert runner.error is None


def test_simulated_time_reads_as_wall_time_from_the_start() -> None:
    runner = PacedRunner(lambda: 100.0, lambda target: False, name="test-pacing", step_s=STEP_S)
    # Bracketed by the wall clock read before the start and after: no bound on how long a
    # loaded machine takes in between.
    before = time.time()
    runner.start()
    try:
        assert before <= runner.epoch() <= time.time()
        assert runner.epoch(90.0) == pytest.approx(runner.epoch() - 10.0)
    finally:
        runner.stop()


def test_speed_must_be_positive() -> None:
    runner = PacedRunner(lambda: 0.0, lambda target: False, name="test-pacing", step_s=STEP_S)
    with pytest.raises(ValueError, match="positive"):
        runner.start(speed=0)
