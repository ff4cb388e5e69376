"""Fixtures any test may use (a recorder, a manual clock, a fake radio), the simavr tier, and
the simulator's kernels compiled before the first test when numba's cache lacks them, so that no
test's timeout counts a compile (minutes on a loaded machine) and the suite says what it is doing
meanwhile."""

from __future__ import annotations

import sys

import pytest

from tests.support.fakes import FakeRadio, ManualClock, Recorder


@pytest.fixture
def recorder() -> Recorder:
    return Recorder()


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock()


@pytest.fixture
def fake_radio(clock: ManualClock) -> FakeRadio:
    return FakeRadio(clock)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Every test that needs the firmware running in simavr is in the simavr tier, whether its
    module asks for the built_images fixture or the test does, so `-m "not simavr"` leaves
    it out without each new test having to say so."""
    for item in items:
        if "built_images" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.simavr)


def pytest_collection_finish(session: pytest.Session) -> None:
    # Collection imported every selected test module: the simulator is among their imports
    # exactly when a selected test may step a world.
    if not any(name.startswith("particlebot.sim.world") for name in sys.modules):
        return
    from particlebot.commands._kernels import prepare_kernels
    from particlebot.sim.warmup import kernels_cached

    if kernels_cached():
        return
    capture = session.config.pluginmanager.getplugin("capturemanager")
    if capture is None:
        prepare_kernels(sys.stderr)
        return
    with capture.global_and_fixture_disabled():
        prepare_kernels(sys.stderr)
