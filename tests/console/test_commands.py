"""The console's command line: what a person types becomes the right frames, or a clear error."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from particlebot.console.commands import CommandError, execute, help_text
from particlebot.protocol import BROADCAST_ID, Param, Ping, SetId, SetParam, Start, State
from particlebot.swarm.api import Swarm
from tests.support.fakes import FakeRadio, status_frame, wait_until


@pytest.fixture
def swarm(fake_radio: FakeRadio) -> Iterator[Swarm]:
    opened = Swarm(fake_radio, log_dir=None, stop_grace=0)
    yield opened
    opened.close()


def hear(swarm: Swarm, radio: FakeRadio, particle: int, **fields: int) -> None:
    radio.inject(status_frame(particle, **fields))
    assert wait_until(lambda: particle in {p.id for p in swarm.particles()})


def test_commands_become_the_right_messages(swarm: Swarm, fake_radio: FakeRadio) -> None:
    execute(swarm, "start B cycle=300 wave=4 update=60 phototaxis=1")
    execute(swarm, "set cycle_steps 75 3")
    execute(swarm, "set 8 20")
    execute(swarm, "setid 254 12")
    execute(swarm, "identify all")
    execute(swarm, "ping 4")
    start, set_one, set_all, set_id, identify, ping = [f.message for f in fake_radio.sent_frames()]
    assert start == Start(
        run_id=1, method=1, cycle_steps=300, wave_size=4, update_interval_s=60, phototaxis=1
    )
    assert set_one == SetParam(target=3, param=int(Param.CYCLE_STEPS), value=75)
    assert set_all == SetParam(target=BROADCAST_ID, param=int(Param.COUNT_TOLERANCE), value=20)
    assert set_id == SetId(target=254, new_id=12)
    assert identify.target == BROADCAST_ID  # type: ignore[union-attr]
    assert ping == Ping(target=4)


def test_the_stop_and_start_commands_say_how_they_are_repeated(
    swarm: Swarm, fake_radio: FakeRadio
) -> None:
    hear(swarm, fake_radio, 1, state=int(State.CYCLING))
    assert "4 copies in 0.3 s" in execute(swarm, "stop")
    assert "1 known particle(s)" in execute(swarm, "start D")


def test_stop_just_after_the_console_started_says_it_keeps_going(fake_radio: FakeRadio) -> None:
    swarm = Swarm(fake_radio, log_dir=None)
    try:
        assert "for 10 s whatever is heard" in execute(swarm, "stop")
    finally:
        swarm.close()


def test_setid_refuses_an_id_in_use_unless_forced(swarm: Swarm, fake_radio: FakeRadio) -> None:
    hear(swarm, fake_radio, 3)
    hear(swarm, fake_radio, 5)
    with pytest.raises(CommandError, match=r"Id 5 is in use.*setid 3 5 force"):
        execute(swarm, "setid 3 5")
    assert fake_radio.sent == []
    assert execute(swarm, "setid 3 5 force") == "SET_ID 3 -> 5 sent"
    assert fake_radio.sent_frames()[-1].message == SetId(target=3, new_id=5)
    assert 5 not in {p.id for p in swarm.particles()}  # the row of the one it replaces went


def test_forget_drops_a_particle_by_hand(swarm: Swarm, fake_radio: FakeRadio) -> None:
    hear(swarm, fake_radio, 7)
    assert execute(swarm, "forget 7") == ""
    assert "Particle 7 forgotten: no longer expected" in swarm.notes()[-1]
    assert swarm.particles() == []
    assert execute(swarm, "forget 7") == "No particle 7 to forget"
    assert fake_radio.sent == []


@pytest.mark.parametrize(
    ("line", "complaint"),
    [
        ("start E", "use A, B, C or D"),
        ("start cycle=5", "cycle must be 10..3000"),
        ("start speed=3", "takes cycle="),
        ("set nonsense 3", "params"),
        ("set cycle_steps 99999", "10..3000"),
        ("setid all 4", "one particle"),
        ("setid 3 254", "1..253"),
        ("identify", "usage"),
        ("forget", "usage"),
        ("fly", "help"),
    ],
)
def test_bad_commands_say_how_to_write_them(swarm: Swarm, line: str, complaint: str) -> None:
    with pytest.raises(CommandError, match=complaint):
        execute(swarm, line)
    assert swarm.tracker.run_id == 0


def test_help_lists_every_command() -> None:
    text = help_text()
    for command in ("start", "stop", "set", "get", "identify", "setid", "forget", "ping", "quit"):
        assert f"\n{command}" in f"\n{text}"
