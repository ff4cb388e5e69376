"""Fixtures any test may use: a recorder of what a session hands on, a manual clock, a radio."""

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
