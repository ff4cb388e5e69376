"""The console model: the particle table, flags, and START/STOP repeated until confirmed."""

from __future__ import annotations

import pytest

from particlebot.console.commands import CommandError, execute, help_text
from particlebot.console.model import ConsoleModel
from particlebot.protocol import (
    BROADCAST_ID,
    DEFINITION_HASH,
    Message,
    Method,
    Param,
    ParamResult,
    ParamValue,
    Ping,
    SetId,
    SetParam,
    Start,
    State,
    Stop,
    decode_frame,
    encode_frame,
)
from particlebot.session import ReceivedFrame
from tests.host.fakes import ManualClock, status_frame


class Sink:
    def __init__(self) -> None:
        self.messages: list[Message] = []
        self.notes: list[str] = []

    def send(self, message: Message) -> None:
        self.messages.append(message)

    def note(self, text: str) -> None:
        self.notes.append(text)

    def types(self) -> list[str]:
        return [type(m).__name__ for m in self.messages]


@pytest.fixture
def sink() -> Sink:
    return Sink()


@pytest.fixture
def model(sink: Sink, clock: ManualClock) -> ConsoleModel:
    return ConsoleModel(sink, clock)


def hear(model: ConsoleModel, clock: ManualClock, raw: bytes, source: str | None = None) -> None:
    model.on_frame(ReceivedFrame(clock(), source, decode_frame(raw)))


def test_a_status_adds_a_row_with_its_fields(model: ConsoleModel, clock: ManualClock) -> None:
    hear(model, clock, status_frame(4, state=int(State.CYCLING), s_n=3, intensity=812))
    (row,) = model.rows()
    assert (row.id, row.state, row.intensity) == (4, State.CYCLING, 812)
    assert row.status is not None and row.status.s_n == 3
    assert not row.hash_mismatch()


def test_a_particle_silent_for_three_status_periods_is_flagged(
    model: ConsoleModel, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(1))
    clock.advance(2.0)
    assert not model.rows()[0].silent(clock(), model.silent_after)
    clock.advance(5.0)
    assert model.rows()[0].silent(clock(), model.silent_after)


def test_a_different_definition_hash_is_flagged_and_noted_once(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    other = DEFINITION_HASH ^ 0x1
    hear(model, clock, status_frame(2, definition_hash=other))
    hear(model, clock, status_frame(2, definition_hash=other))
    assert model.rows()[0].hash_mismatch()
    assert sum("reflash" in note for note in sink.notes) == 1


def test_unassigned_particles_are_told_apart_by_radio_address(
    model: ConsoleModel, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(254), source="0013A20000000001")
    hear(model, clock, status_frame(254), source="0013A20000000002")
    assert len(model.rows()) == 2
    assert any("setid 254" in note.text for note in model.notes)


def test_frames_from_a_base_station_are_not_particles(
    model: ConsoleModel, clock: ManualClock
) -> None:
    hear(model, clock, encode_frame(Stop(), 0, 1))
    assert model.rows() == []


def test_stop_is_repeated_until_every_particle_reports_it_has_stopped(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    for particle in (1, 2, 3):
        hear(model, clock, status_frame(particle, state=int(State.CYCLING)))
    campaign = model.stop()
    assert sink.types() == ["Stop", "Ping"]
    clock.advance(1.0)
    model.poll()
    assert sink.types() == ["Stop", "Ping"] * 2  # nobody answered: again
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    hear(model, clock, status_frame(2, state=int(State.IDLE)))
    model.poll()
    assert not campaign.done
    clock.advance(1.0)
    model.poll()
    assert sink.types()[-2:] == ["Stop", "Ping"]  # particle 3 has not obeyed yet
    hear(model, clock, status_frame(3, state=int(State.DONE)))
    assert campaign.done and campaign.success
    assert campaign.confirmed == {"1", "2", "3"}
    assert "confirmed by all 3" in sink.notes[-1]


def test_a_status_from_before_the_stop_does_not_confirm_it(
    model: ConsoleModel, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    clock.advance(0.5)
    campaign = model.stop()
    model.poll()
    assert not campaign.done


def test_stop_is_not_repeated_once_every_particle_obeys_it_only_pinged(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    hear(model, clock, status_frame(2, state=int(State.PAUSED)))
    campaign = model.stop()
    hear(model, clock, status_frame(1, state=int(State.STOPPING)))
    hear(model, clock, status_frame(2, state=int(State.STOPPING)))
    clock.advance(1.0)
    model.poll()
    # A repeated STOP would restart their contraction; a PING just asks how it went.
    assert sink.types() == ["Stop", "Ping", "Ping"]
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    hear(model, clock, status_frame(2, state=int(State.IDLE)))
    assert campaign.success


def test_stop_names_the_particles_that_never_confirmed(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    for particle in (5, 6, 7):
        hear(model, clock, status_frame(particle, state=int(State.CYCLING)))
    campaign = model.stop()
    hear(model, clock, status_frame(6, state=int(State.IDLE)))
    for _ in range(12):
        clock.advance(1.0)
        model.poll()
    assert campaign.done and not campaign.success
    assert "particle(s) 5, 7" in campaign.outcome
    assert sink.types().count("Stop") == model.stop_timeout  # one per second until the timeout


def test_stop_with_no_particles_known_says_so(model: ConsoleModel, clock: ManualClock) -> None:
    campaign = model.stop()
    clock.advance(model.stop_timeout)
    model.poll()
    assert campaign.done and "no particles known" in campaign.outcome


def test_start_takes_a_new_run_id_and_is_resent_until_each_reports_it(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(1, run_id=7))
    hear(model, clock, status_frame(2, run_id=3))
    campaign = model.start(Method.LINEAR, cycle_steps=75)
    start = sink.messages[0]
    assert isinstance(start, Start)
    assert (start.run_id, start.method, start.cycle_steps) == (8, Method.LINEAR, 75)
    hear(model, clock, status_frame(1, run_id=8, state=int(State.ESTIMATING)))
    clock.advance(model.start_interval)
    model.poll()
    assert [type(m).__name__ for m in sink.messages] == ["Start", "Start"]
    assert sink.messages[1] == start  # the same run_id, which particles in the run ignore
    hear(model, clock, status_frame(2, run_id=8, state=int(State.ESTIMATING)))
    assert campaign.success


def test_stop_cancels_a_start_still_being_resent(
    model: ConsoleModel, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(1))
    start = model.start(Method.COUNTING)
    model.stop()
    assert start.done and not start.success
    clock.advance(model.start_interval)
    model.poll()
    assert "Start" not in sink.types()[1:]


def test_param_values_are_shown_as_notes(model: ConsoleModel, clock: ManualClock) -> None:
    reply = ParamValue(param=int(Param.CYCLE_STEPS), result=int(ParamResult.BUSY), value=150)
    hear(model, clock, encode_frame(reply, 3, 0))
    assert model.notes[-1].text == "Particle 3: CYCLE_STEPS = 150 (BUSY)"


def test_commands_become_the_right_messages(model: ConsoleModel, sink: Sink) -> None:
    execute(model, "start B cycle=300 wave=4 update=60 phototaxis=1")
    execute(model, "set cycle_steps 75 3")
    execute(model, "set 8 20")
    execute(model, "setid 254 12")
    execute(model, "identify all")
    execute(model, "ping 4")
    start, set_one, set_all, set_id, identify, ping = sink.messages
    assert start == Start(
        run_id=1, method=1, cycle_steps=300, wave_size=4, update_interval_s=60, phototaxis=1
    )
    assert set_one == SetParam(target=3, param=int(Param.CYCLE_STEPS), value=75)
    assert set_all == SetParam(target=BROADCAST_ID, param=int(Param.COUNT_TOLERANCE), value=20)
    assert set_id == SetId(target=254, new_id=12)
    assert identify.target == BROADCAST_ID  # type: ignore[attr-defined]
    assert ping == Ping(target=4)


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
        ("fly", "help"),
    ],
)
def test_bad_commands_say_how_to_write_them(model: ConsoleModel, line: str, complaint: str) -> None:
    with pytest.raises(CommandError, match=complaint):
        execute(model, line)
    assert model.run_id == 0


def test_help_lists_every_command() -> None:
    text = help_text()
    for command in ("start", "stop", "set", "get", "identify", "setid", "ping", "quit"):
        assert f"\n{command}" in f"\n{text}"
