"""Fixtures of the host tests."""

from __future__ import annotations

import pytest

from tests.host.fakes import FakeRadio, ManualClock, Recorder


@pytest.fixture
def recorder() -> Recorder:
    return Recorder()


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock()


@pytest.fixture
def fake_radio(clock: ManualClock) -> FakeRadio:
    return FakeRadio(clock)
