"""Fixtures any test may use (a recorder, a manual clock, a fake radio) and the simavr tier."""

from __future__ import annotations

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
