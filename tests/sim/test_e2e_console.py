"""The console's `emulated://K` radio: URL checks, and a console session driving the swarm."""

from __future__ import annotations

import time
from collections.abc import Callable

import pytest

from particlebot.commands._common import station
from particlebot.protocol import Method, State
from particlebot.radio import InvalidRadioUrlError, RadioError, open_radio, parse_radio_url
from particlebot.radio.emulated import swarm_config_from_url


def wait_for(
    condition: Callable[[], bool], timeout_s: float, poll: Callable[[], None], every_s: float = 0.5
) -> bool:
    """Calls poll every every_s (a PING, or the console's campaign step) until condition() holds
    or timeout_s of wall time pass."""
    end = time.monotonic() + timeout_s
    next_poll = 0.0
    while time.monotonic() < end:
        if time.monotonic() >= next_poll:
            poll()
            next_poll = time.monotonic() + every_s
        if condition():
            return True
        time.sleep(0.02)
    return condition()


@pytest.mark.parametrize(
    "url",
    [
        "emulated://0",
        "emulated://33",
        "emulated://five",
        "emulated://5?loss=1.5",
        "emulated://5?delay_ms=-1",
        "emulated://5?lamp=0,0",
        "emulated://5?colour=red",
        "emulated://5?speed=0",
    ],
)
def test_bad_emulated_urls_are_refused_with_advice(url: str) -> None:
    with pytest.raises(InvalidRadioUrlError):
        open_radio(url)


def test_emulated_url_options_reach_the_swarm_configuration() -> None:
    config = swarm_config_from_url(
        parse_radio_url("emulated://7?loss=0.2&delay_ms=5&spacing=0.2&start=0.3&seed=4")
    )
    assert config.count == 7
    assert config.loss == 0.2
    assert config.delay_us == 5000
    assert config.spacing == 0.2 and config.start == 0.3
    assert config.seed == 4
    assert not config.keep_history  # a console may run for hours


def test_a_missing_firmware_image_is_reported_with_the_command_that_builds_it() -> None:
    with pytest.raises(RadioError, match="make firmware harness"):
        open_radio("emulated://2?elf=build/firmware/no-such-image.elf")


@pytest.mark.usefixtures("built_images")
def test_console_session_finds_starts_and_stops_emulated_particles() -> None:
    with station("emulated://3?speed=max", None) as base:
        model = base.model

        def ids() -> list[int]:
            return sorted(row.id for row in model.rows())

        assert wait_for(lambda: ids() == [1, 2, 3], 60, model.ping), ids()
        start = model.start(Method.COUNTING, cycle_steps=75)
        assert wait_for(lambda: start.done, 60, model.poll, 0.05), start.outcome
        assert start.success, start.outcome

        def estimated() -> bool:
            rows = model.rows()
            return all(row.status is not None and row.status.s_n > 0 for row in rows)

        assert wait_for(estimated, 60, model.ping)
        assert [row.status.s_n for row in model.rows() if row.status] == [1, 2, 3]
        stop = model.stop()
        assert wait_for(lambda: stop.done, 60, model.poll, 0.05), stop.outcome
        assert stop.success, stop.outcome
        assert all(row.state == State.IDLE for row in model.rows())
