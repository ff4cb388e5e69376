"""The swarm tracker: the particle table, flags, and START/STOP repeated until confirmed."""

from __future__ import annotations

import pytest

from particlebot.protocol import (
    DEFINITION_HASH,
    UNASSIGNED_ID,
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
from particlebot.radio import Packet, PortLostError, ReadOnlyRadioError
from particlebot.session import ReceivedFrame
from particlebot.swarm.campaigns import Verdict
from particlebot.swarm.tracker import Campaign, IdInUseError, Rename, SwarmTracker
from tests.support.fakes import ManualClock, status_frame


class Sink:
    """Keeps what the model sends, with the clock's time of each."""

    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.messages: list[Message] = []
        self.times: list[float] = []
        self.notes: list[str] = []

    def send(self, message: Message) -> None:
        self.messages.append(message)
        self.times.append(self.clock())

    def note(self, text: str) -> None:
        self.notes.append(text)

    def types(self) -> list[str]:
        return [type(m).__name__ for m in self.messages]

    def since(self, count: int) -> list[str]:
        """What was sent after the first count messages: "Stop", "Start", "Ping 3"."""
        return [_describe(m) for m in self.messages[count:]]

    def offsets(self, kind: type[Message], origin: float) -> list[float]:
        """When each message of a kind went out, in seconds after origin (to the millisecond)."""
        return [
            round(at - origin, 3)
            for at, m in zip(self.times, self.messages, strict=True)
            if isinstance(m, kind)
        ]


def _describe(message: Message) -> str:
    if isinstance(message, Ping):
        return f"Ping {message.target}"
    return type(message).__name__


@pytest.fixture
def sink(clock: ManualClock) -> Sink:
    return Sink(clock)


@pytest.fixture
def model(sink: Sink, clock: ManualClock) -> SwarmTracker:
    return SwarmTracker(sink, clock)


def hear(model: SwarmTracker, clock: ManualClock, raw: bytes, source: str | None = None) -> None:
    """The frame arrives; then the console's next poll (at the same moment) looks at it."""
    model.on_frame(ReceivedFrame(clock(), source, decode_frame(raw)))
    model.poll()


def test_a_status_adds_a_row_with_its_fields(model: SwarmTracker, clock: ManualClock) -> None:
    hear(model, clock, status_frame(4, state=int(State.CYCLING), s_n=3, intensity=812))
    (row,) = model.rows()
    assert (row.id, row.state, row.intensity) == (4, State.CYCLING, 812)
    assert row.status is not None and row.status.s_n == 3
    assert not row.hash_mismatch()


def test_a_particle_silent_for_three_status_periods_is_flagged(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(1))
    clock.advance(2.0)
    assert not model.rows()[0].silent(clock(), model.silent_after)
    clock.advance(5.0)
    assert model.rows()[0].silent(clock(), model.silent_after)


def test_a_different_definition_hash_is_flagged_and_noted_once(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    other = DEFINITION_HASH ^ 0x1
    hear(model, clock, status_frame(2, definition_hash=other))
    hear(model, clock, status_frame(2, definition_hash=other))
    assert model.rows()[0].hash_mismatch()
    assert sum("reflash" in note for note in sink.notes) == 1


def test_unassigned_particles_are_told_apart_by_radio_address(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(254), source="0013A20000000001")
    hear(model, clock, status_frame(254), source="0013A20000000002")
    assert len(model.rows()) == 2
    assert any("setid 254" in note.text for note in model.notes)


def test_frames_from_a_base_station_are_not_particles(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, encode_frame(Stop(), 0, 1))
    assert model.rows() == []


def run(model: SwarmTracker, clock: ManualClock, seconds: float, every: float = 0.05) -> None:
    """Polls the model every `every` seconds for `seconds`, as the console's timer does."""
    for _ in range(round(seconds / every)):
        clock.advance(every)
        model.poll()


def hear_all(model: SwarmTracker, clock: ManualClock, ids: range, state: State) -> None:
    for particle in ids:
        hear(model, clock, status_frame(particle, state=int(state)))


def stop_running(model: SwarmTracker, clock: ManualClock, ids: range) -> Campaign:
    """Particles ids report CYCLING; then STOP, and polls until its burst has gone out."""
    hear_all(model, clock, ids, State.CYCLING)
    campaign = model.stop()
    run(model, clock, 0.35)
    return campaign


def test_stop_goes_out_four_times_in_three_tenths_of_a_second_then_pings_each_particle(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear_all(model, clock, range(1, 4), State.CYCLING)
    origin = clock()
    model.stop()
    assert sink.since(0) == ["Stop"]  # at once, without waiting for a poll
    run(model, clock, 0.4)
    assert sink.offsets(Stop, origin) == [0.0, 0.1, 0.2, 0.3]
    # The PINGs follow the last copy, so each STATUS they ask for shows the STOP obeyed.
    assert sink.since(4) == ["Ping 1", "Ping 2", "Ping 3"]
    assert sink.offsets(Ping, origin) == [0.3] * 3


def test_after_a_late_poll_the_rest_of_the_burst_goes_out_one_copy_a_poll(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear_all(model, clock, range(1, 2), State.CYCLING)
    origin = clock()
    model.stop()
    clock.advance(0.25)  # the copies due at 0.1 and 0.2 were missed: one goes now, not two
    model.poll()
    run(model, clock, 0.2)
    # None is dropped and none doubled: every copy stands a fresh chance on the air.
    assert sink.offsets(Stop, origin) == [0.0, 0.25, 0.3, 0.35]


def test_stop_is_repeated_every_half_second_until_every_particle_reports_it_has_stopped(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    origin = clock()
    campaign = stop_running(model, clock, range(1, 4))
    hear_all(model, clock, range(1, 3), State.IDLE)
    sent = len(sink.messages)
    run(model, clock, 0.5)
    # Particle 3 has not answered: it may have missed every copy. Those that have stopped
    # are not asked again.
    assert sink.since(sent) == ["Stop", "Ping 3"]
    assert sink.offsets(Stop, origin)[-1] == 0.8
    assert not campaign.done
    run(model, clock, 0.5)
    assert sink.offsets(Stop, origin)[-1] == 1.3
    hear(model, clock, status_frame(3, state=int(State.DONE)))
    assert campaign.done and campaign.success
    assert campaign.confirmed == {"1", "2", "3"}
    assert "confirmed by all 3" in sink.notes[-1]


def test_a_status_from_before_the_stop_does_not_confirm_it(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    clock.advance(0.5)
    campaign = model.stop()
    run(model, clock, 1.0)
    assert not campaign.done


def test_stop_is_not_repeated_once_every_particle_obeys_it_only_pinged(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = stop_running(model, clock, range(1, 3))
    hear_all(model, clock, range(1, 3), State.STOPPING)
    sent = len(sink.messages)
    run(model, clock, 0.5)
    # A repeated STOP would restart their contraction; a PING just asks how it went.
    assert sink.since(sent) == ["Ping 1", "Ping 2"]
    hear_all(model, clock, range(1, 3), State.IDLE)
    assert campaign.success


def stop_answered_at_once(model: SwarmTracker, clock: ManualClock) -> Campaign:
    """Particle 1 reports CYCLING; STOP; 0.05 s later (before the burst is out) it is IDLE."""
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    campaign = model.stop()
    clock.advance(0.05)
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    return campaign


def test_the_whole_burst_goes_out_even_when_every_known_particle_has_stopped(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = stop_answered_at_once(model, clock)
    # Particles the console has not heard yet may be out there; only the burst can reach them.
    assert not campaign.done
    run(model, clock, 0.4)
    assert sink.types().count("Stop") == 4
    assert campaign.done and campaign.success


def test_a_particle_whose_latest_status_is_no_longer_stopped_is_waited_for_again(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = stop_answered_at_once(model, clock)
    assert campaign.confirmed == {"1"}
    run(model, clock, 0.2)
    # A later copy of the burst found it stopped, and for a moment it is STOPPING again.
    hear(model, clock, status_frame(1, state=int(State.STOPPING)))
    run(model, clock, 0.1)
    assert not campaign.done and campaign.pending == {"1"}
    assert sink.since(4) == ["Ping 1"]
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    assert campaign.done and campaign.success


def test_stop_names_the_particles_that_never_confirmed(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear_all(model, clock, range(5, 8), State.CYCLING)
    origin = clock()
    campaign = model.stop()
    clock.advance(0.05)
    hear(model, clock, status_frame(6, state=int(State.IDLE)))
    run(model, clock, model.stop_timeout + 0.1)
    assert campaign.done and not campaign.success
    assert "particle(s) 5, 7" in campaign.outcome
    # After the burst, every half second until the timeout.
    repeats = sink.offsets(Stop, origin)[4:]
    assert repeats == [round(0.8 + 0.5 * k, 3) for k in range(19)]


def test_stop_with_no_particles_known_ends_after_its_burst_unconfirmed_never_a_success(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = model.stop()
    run(model, clock, 0.4)
    assert sink.types() == ["Stop"] * 4
    # Silence is no answer: nothing says anyone stopped.
    assert campaign.done and not campaign.success
    assert campaign.verdict is Verdict.UNCONFIRMED
    assert campaign.outcome == "STOP sent; nobody confirmed it"
    assert model.notes[-1].level == "warning"


@pytest.mark.parametrize(
    ("roster", "listened_s", "verdict"),
    [
        (None, 3.0, Verdict.UNCONFIRMED),  # heard for 3 s: others may be out there, moving
        (None, 10.0, Verdict.CONFIRMED),  # heard for as long as listen_s asks
        (range(1, 4), 3.0, Verdict.CONFIRMED),  # the fleet says who there is
    ],
)
def test_stop_is_confirmed_only_by_a_base_station_that_knows_the_swarm(
    sink: Sink, clock: ManualClock, roster: range | None, listened_s: float, verdict: Verdict
) -> None:
    model = SwarmTracker(sink, clock, roster=roster, listen_s=10.0)
    clock.advance(listened_s)
    campaign = stop_running(model, clock, range(1, 4))
    hear_all(model, clock, range(1, 4), State.IDLE)
    assert campaign.done and campaign.verdict is verdict
    assert campaign.success == (verdict is Verdict.CONFIRMED)
    if verdict is Verdict.UNCONFIRMED:
        assert campaign.outcome.startswith("STOP confirmed by the 3 particle(s) heard, but the ")
        assert "listened for only 3.0 s" in campaign.outcome


def test_pings_go_to_four_particles_a_round_those_asked_least_first(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    stop_running(model, clock, range(1, 7))
    assert sink.since(4) == ["Ping 1", "Ping 2", "Ping 3", "Ping 4"]
    sent = len(sink.messages)
    run(model, clock, 0.5)
    assert sink.since(sent) == ["Stop", "Ping 5", "Ping 6", "Ping 1", "Ping 2"]


def test_one_ping_asks_every_particle_without_an_id(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(3, state=int(State.CYCLING)))
    for source in ("0013A20000000001", "0013A20000000002"):
        hear(model, clock, status_frame(254, state=int(State.CYCLING)), source=source)
    model.stop()
    run(model, clock, 0.35)
    assert sink.since(4) == ["Ping 3", f"Ping {UNASSIGNED_ID}"]


def test_a_stop_burst_must_start_at_once_and_be_in_order(clock: ManualClock) -> None:
    for burst in [(), (0.1, 0.2), (0.0, 0.2, 0.1)]:
        with pytest.raises(ValueError, match="stop_burst"):
            SwarmTracker(None, clock, stop_burst=burst)


def start_with_one_answer(
    model: SwarmTracker, clock: ManualClock, runs: dict[int, int]
) -> Campaign:
    """Particles (id: run) report those runs; START (method B, 75 steps); 0.1 s later the first
    of them reports the new run."""
    for particle, run_id in runs.items():
        hear(model, clock, status_frame(particle, run_id=run_id))
    campaign = model.start(Method.LINEAR, cycle_steps=75)
    clock.advance(0.1)
    first = next(iter(runs))
    hear(model, clock, status_frame(first, run_id=model.run_id, state=int(State.ESTIMATING)))
    return campaign


def test_start_takes_a_new_run_id_and_pings_each_particle_until_it_reports_it(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    origin = clock()
    campaign = start_with_one_answer(model, clock, {1: 7, 2: 3})
    start = sink.messages[0]
    assert isinstance(start, Start)
    assert (start.run_id, start.method, start.cycle_steps) == (8, Method.LINEAR, 75)
    # Each particle is asked at once, behind the START, rather than left to its next STATUS.
    assert sink.since(1) == ["Ping 1", "Ping 2"]
    run(model, clock, 0.45)
    assert sink.since(3) == ["Ping 2"]  # no answer yet: asked again, START not resent
    assert sink.offsets(Ping, origin)[-1] == 0.5
    hear(model, clock, status_frame(2, run_id=8, state=int(State.ESTIMATING)))
    assert campaign.success
    assert "confirmed by all 2" in campaign.outcome


def test_start_is_resent_with_the_same_run_id_when_a_particle_reports_another_run(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = start_with_one_answer(model, clock, {1: 7, 2: 7})
    hear(model, clock, status_frame(2, run_id=7))  # its answer shows it missed START
    run(model, clock, 0.45)
    assert sink.since(3) == ["Start", "Ping 2"]
    assert sink.messages[3] == sink.messages[0]  # the same run_id: particle 1 ignores it
    hear(model, clock, status_frame(2, run_id=8, state=int(State.ESTIMATING)))
    assert campaign.success


def test_start_names_the_particles_that_never_confirmed(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    campaign = start_with_one_answer(model, clock, {1: 2, 4: 2})
    run(model, clock, model.start_timeout + 0.1)
    assert campaign.done and not campaign.success
    assert "START not confirmed within 8 s by particle(s) 4 (1 confirmed)" in campaign.outcome
    assert sink.types().count("Start") == 1  # particle 4 never answered: nothing says it missed


def test_stop_cancels_a_start_still_being_resent(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(1))
    start = model.start(Method.COUNTING)
    model.stop()
    assert start.done and not start.success
    clock.advance(0.1)
    hear(model, clock, status_frame(1, run_id=0))  # "another run": would resend START
    run(model, clock, 2.0)
    assert "Start" not in sink.types()[1:]


# A SET of SERVO_CAL_3 refused with 1285 still in force: the value asked was inside the
# parameter's range, but the nine-point table would no longer rise.
NOT_MONOTONIC = ParamValue(
    param=int(Param.SERVO_CAL_3), result=int(ParamResult.SERVO_TABLE_NOT_MONOTONIC), value=1285
)


def test_param_values_are_shown_as_notes(model: SwarmTracker, clock: ManualClock) -> None:
    reply = ParamValue(param=int(Param.CYCLE_STEPS), result=int(ParamResult.BUSY), value=150)
    hear(model, clock, encode_frame(reply, 3, 0))
    assert model.notes[-1].text == "Particle 3: CYCLE_STEPS = 150 (BUSY: STOP them first)"
    hear(model, clock, encode_frame(NOT_MONOTONIC, 3, 1))
    assert model.notes[-1].text == (
        "Particle 3: SERVO_CAL_3 = 1285 (SERVO_TABLE_NOT_MONOTONIC: SERVO_CAL_0..8 must keep "
        "rising (or falling) from point to point: change the neighbouring points first)"
    )


def test_a_refused_set_says_why_what_to_do_and_what_stays(
    model: SwarmTracker, clock: ManualClock
) -> None:
    # 2000 is inside SERVO_CAL_3's 500..2500: the table it would make is what is wrong.
    hear_all(model, clock, range(1, 4), State.IDLE)
    model.set_param(Param.SERVO_CAL_3, 2000, 2)
    hear(model, clock, encode_frame(NOT_MONOTONIC, 2, 1))
    assert model.notes[-1].text == (
        "Particle 2: SET SERVO_CAL_3 = 2000 refused, SERVO_TABLE_NOT_MONOTONIC: SERVO_CAL_0..8 "
        "must keep rising (or falling) from point to point: change the neighbouring points "
        "first; it stays 1285"
    )
    model.set_param(Param.SERVO_CAL_3, 2000)
    for particle in range(1, 4):
        hear(model, clock, encode_frame(NOT_MONOTONIC, particle, 2))
    assert model.notes[-1].text.startswith(
        "SET SERVO_CAL_3 = 2000: 0/3 OK; SERVO_TABLE_NOT_MONOTONIC: 1-3 (SERVO_CAL_0..8 must keep"
    )


# ---- answers to SET_PARAM and GET_PARAM --------------------------------------------------------


def answer(
    model: SwarmTracker, clock: ManualClock, particle: int, result: ParamResult, value: int
) -> None:
    reply = ParamValue(param=int(Param.CYCLE_STEPS), result=int(result), value=value)
    hear(model, clock, encode_frame(reply, particle, 0))


def test_answers_to_a_broadcast_set_are_summarised_in_one_line(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear_all(model, clock, range(1, 11), State.IDLE)
    notes_before = len(model.notes)
    model.set_param(Param.CYCLE_STEPS, 300)
    for particle in range(1, 11):
        clock.advance(0.06)
        answer(model, clock, particle, ParamResult.OK, 300)
    (summary,) = [note.text for note in list(model.notes)[notes_before:]]
    assert summary == "SET CYCLE_STEPS = 300: 10/10 OK"
    assert sink.notes[-1] == summary  # and it goes into the log


def asked_for(model: SwarmTracker) -> float:
    """How long a query waits at most: the first wait, then a retry by id each time."""
    return model.param_timeout + (model.param_attempts - 1) * model.param_retry


def test_refusals_and_silence_are_named_in_the_summary(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear_all(model, clock, range(1, 11), State.IDLE)
    notes_before = len(model.notes)
    model.set_param(Param.CYCLE_STEPS, 300)
    for particle in (1, 2, 4, 5, 6, 8, 10):
        answer(model, clock, particle, ParamResult.OK, 300)
    for particle in (3, 7):
        answer(model, clock, particle, ParamResult.BUSY, 150)
    sent = len(sink.messages)
    run(model, clock, model.param_timeout)
    # Particle 9 may have missed the broadcast, or its answer was lost: it is asked by id.
    assert sink.messages[sent:] == [SetParam(target=9, param=int(Param.CYCLE_STEPS), value=300)]
    assert list(model.notes)[notes_before:] == []
    run(model, clock, asked_for(model) - model.param_timeout)
    assert len(sink.messages) == sent + model.param_attempts - 1
    (summary,) = [note for note in list(model.notes)[notes_before:]]
    assert summary.text == (
        "SET CYCLE_STEPS = 300: 7/10 OK; BUSY: 3, 7 (STOP them first); no answer from 9"
    )
    assert summary.level == "warning"


def test_a_particle_asked_again_by_id_completes_the_summary(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear_all(model, clock, range(1, 4), State.IDLE)
    query = model.set_param(Param.CYCLE_STEPS, 300)
    for particle in (1, 2):
        answer(model, clock, particle, ParamResult.OK, 300)
    run(model, clock, model.param_timeout + model.param_retry)
    answer(model, clock, 3, ParamResult.OK, 300)
    assert query.done and query.ok
    assert model.notes[-1].text == "SET CYCLE_STEPS = 300: 3/3 OK"


def test_a_broadcast_get_groups_the_particles_by_value(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear_all(model, clock, range(1, 11), State.IDLE)
    model.get_param(Param.CYCLE_STEPS)
    for particle in range(1, 11):
        answer(model, clock, particle, ParamResult.OK, 300 if particle in (4, 9) else 150)
    assert model.notes[-1].text == "GET CYCLE_STEPS: 150 on 1-3, 5-8, 10; 300 on 4, 9"


def test_a_get_nobody_answers_says_so_after_its_timeout(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear_all(model, clock, range(1, 3), State.IDLE)
    model.get_param(Param.CYCLE_STEPS)
    run(model, clock, asked_for(model) - 0.1)
    assert not model.notes
    run(model, clock, 0.1)
    assert model.notes[-1].text == "GET CYCLE_STEPS: no particle answered within 6.5 s"
    model.get_param(Param.CYCLE_STEPS, 7)
    run(model, clock, asked_for(model))
    assert model.notes[-1].text == "GET CYCLE_STEPS to particle 7: no answer within 6.5 s"


def test_the_answer_of_one_particle_asked_by_id_is_one_line(
    model: SwarmTracker, clock: ManualClock
) -> None:
    model.get_param(Param.CYCLE_STEPS, 3)
    answer(model, clock, 3, ParamResult.OK, 150)
    assert model.notes[-1].text == "Particle 3: CYCLE_STEPS = 150 (OK)"


# ---- resets ------------------------------------------------------------------------------------


def test_a_particle_that_resets_during_a_run_is_flagged_with_the_cause(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(4, state=int(State.CYCLING), run_id=3, uptime_ms=60_000))
    clock.advance(2.0)
    # A brown-out under servo load: back as IDLE, one more reset counted, uptime from zero.
    hear(model, clock, status_frame(4, state=int(State.IDLE), resets=2, last_reset_cause=0x04))
    (row,) = model.rows()
    assert row.reset_in_run == 3
    assert model.notes[-1].level == "error"
    assert "Particle 4 reset during run 3 (brown-out" in model.notes[-1].text
    model.start(Method.COUNTING)
    assert row.reset_in_run is None  # a new run starts with a clean slate


def test_a_reset_outside_a_run_is_noted_but_not_flagged(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(4, uptime_ms=60_000))
    hear(model, clock, status_frame(4, resets=2, last_reset_cause=0x01))
    assert model.rows()[0].reset_in_run is None
    assert model.notes[-1].text == (
        "Particle 4 reset (power-on: it was switched off and on, or lost power)"
    )


def test_a_reset_with_a_saturated_counter_is_still_seen_by_the_uptime(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(4, state=int(State.PAUSED), resets=255, uptime_ms=9_000))
    hear(model, clock, status_frame(4, resets=255, uptime_ms=400, last_reset_cause=0x08))
    assert model.rows()[0].reset_in_run == 0
    assert "watchdog" in model.notes[-1].text


# ---- a radio that hears nothing, one that cannot send --------------------------------------------


def test_a_radio_that_hears_nothing_gets_a_hint_once(sink: Sink, clock: ManualClock) -> None:
    model = SwarmTracker(sink, clock, quiet_hint="Check the baud, PAN ID and channel.")
    run(model, clock, 4.9)
    assert not model.notes
    run(model, clock, 10.0)
    assert [note.text for note in model.notes] == [
        "Nothing heard for 5 s. Check the baud, PAN ID and channel."
    ]


def test_a_radio_that_hears_something_gets_no_hint(sink: Sink, clock: ManualClock) -> None:
    model = SwarmTracker(sink, clock, quiet_hint="Check the baud, PAN ID and channel.")
    model.on_packet(Packet(b"\x00", None, clock()))
    run(model, clock, 10.0)
    assert not model.notes


class ReadOnlySink(Sink):
    def send(self, message: Message) -> None:
        raise ReadOnlyRadioError("This is a replay")


class LostPortSink(Sink):
    def send(self, message: Message) -> None:
        raise PortLostError("port gone")


def test_a_radio_that_can_never_send_ends_a_campaign_with_one_message(clock: ManualClock) -> None:
    model = SwarmTracker(ReadOnlySink(clock), clock)
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    campaign = model.stop()
    run(model, clock, 3.0)
    assert campaign.done and not campaign.success
    assert [note.text for note in model.notes if "send" in note.text] == [
        "Could not send STOP: This is a replay"
    ]


def test_a_lost_port_is_reported_once_per_campaign_not_once_per_resend(
    clock: ManualClock,
) -> None:
    model = SwarmTracker(LostPortSink(clock), clock)
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    campaign = model.stop()
    run(model, clock, 3.0)
    assert not campaign.done  # the port may come back: it keeps trying
    assert len([note for note in model.notes if "Could not send" in note.text]) == 1


# ---- who is in the swarm: grace period, largest group, duplicates, renames ----------------------


def test_just_after_the_start_stop_keeps_going_out_and_asks_everyone(
    sink: Sink, clock: ManualClock
) -> None:
    model = SwarmTracker(sink, clock, stop_grace=10.0)
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    origin = clock()
    campaign = model.stop()
    run(model, clock, 0.4)
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    run(model, clock, 5.0)
    # Particle 1 confirmed long ago, but others may be out there: STOP every 0.5 s, and a
    # PING to every particle each second, until the grace period is over.
    assert not campaign.done
    stops = sink.offsets(Stop, origin)
    assert stops[4:] == [round(0.8 + 0.5 * k, 3) for k in range(len(stops) - 4)]
    broadcast_pings = [m for m in sink.messages if isinstance(m, Ping) and m.target == 255]
    assert len(broadcast_pings) >= 4
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    run(model, clock, 5.0)
    assert campaign.done and campaign.success
    assert "confirmed by all 1 particles in 10.0 s" in campaign.outcome


def test_a_particle_first_heard_during_a_stop_must_confirm_it_too(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(1, state=int(State.CYCLING)))
    campaign = model.stop()
    clock.advance(0.1)
    hear(model, clock, status_frame(1, state=int(State.IDLE)))
    hear(model, clock, status_frame(2, state=int(State.CYCLING)))  # missed the first copy
    run(model, clock, 0.5)
    assert not campaign.done and campaign.pending == {"2"}
    hear(model, clock, status_frame(2, state=int(State.IDLE)))
    assert campaign.done and campaign.success and campaign.confirmed == {"1", "2"}


def test_a_run_reported_by_a_group_sets_how_many_must_confirm_stop(
    model: SwarmTracker, clock: ManualClock
) -> None:
    for particle in (1, 2):
        hear(model, clock, status_frame(particle, state=int(State.CYCLING), group_size=3))
    campaign = model.stop()
    clock.advance(0.1)
    hear_all(model, clock, range(1, 3), State.IDLE)
    run(model, clock, model.stop_timeout)
    assert campaign.done and not campaign.success
    assert "2 particle(s) confirmed, but 3 were seen together; 1 never answered" in (
        campaign.outcome
    )


def test_two_clocks_under_one_id_on_a_transparent_link_are_a_duplicate(
    model: SwarmTracker, clock: ManualClock
) -> None:
    hear(model, clock, status_frame(5, uptime_ms=100_000, resets=3))
    clock.advance(1.0)
    assert not model.rows()[0].duplicate
    # Another particle 5, switched on 30 s ago: its uptime is not this one's.
    hear(model, clock, status_frame(5, uptime_ms=30_000, resets=3))
    (row,) = model.rows()
    assert row.duplicate == (
        "two particles answer as 5: its uptime jumped from 100 s to 30 s in 1 s"
    )
    assert model.notes[-1].level == "error" and "DUPLICATE id 5" in model.notes[-1].text
    assert row.reset_in_run is None  # not taken for a reset
    campaign = model.stop()
    clock.advance(0.1)
    hear(model, clock, status_frame(5, state=int(State.IDLE), uptime_ms=101_000, resets=3))
    run(model, clock, model.stop_timeout)
    # Which of the two answered cannot be told: STOP is never confirmed for them.
    assert campaign.done and not campaign.success
    assert model.unconfirmed(campaign) == [
        (5, f"duplicate id: {row.duplicate}; their answers cannot be told apart")
    ]


def test_a_reset_is_not_taken_for_a_duplicate(model: SwarmTracker, clock: ManualClock) -> None:
    hear(model, clock, status_frame(5, uptime_ms=100_000, resets=3))
    clock.advance(2.0)
    hear(model, clock, status_frame(5, uptime_ms=1_200, resets=4, last_reset_cause=0x08))
    clock.advance(2.0)
    hear(model, clock, status_frame(5, uptime_ms=3_200, resets=4))
    assert not model.rows()[0].duplicate
    assert "Particle 5 reset (watchdog" in model.notes[-1].text


def test_a_particle_renamed_from_here_on_a_transparent_link_leaves_no_row(
    model: SwarmTracker, clock: ManualClock, sink: Sink
) -> None:
    hear(model, clock, status_frame(3, uptime_ms=50_000))
    hear(model, clock, status_frame(4, uptime_ms=60_000))
    with pytest.raises(IdInUseError, match="id 4 is in use"):
        model.set_id(3, 4)
    model.set_id(3, 9)
    assert sink.messages[-1] == SetId(target=3, new_id=9)
    clock.advance(0.05)
    hear(model, clock, status_frame(9, uptime_ms=50_050))  # its answer, under the new id
    assert [row.id for row in model.rows()] == [4, 9]
    assert model.take_renames() == [Rename(3, 9, None)]


def test_two_particles_switched_on_together_are_told_by_their_frame_numbers(
    model: SwarmTracker, clock: ManualClock
) -> None:
    # Same uptime, same reset count: but each numbers its own frames.
    for step, seq in enumerate((40, 38)):
        clock.advance(1.0)
        hear(model, clock, status_frame(5, seq=seq, uptime_ms=60_000 + 1000 * step))
    assert model.rows()[0].duplicate == (
        "two particles answer as 5: its frame numbers went back from 40 to 38 with no reset"
    )


def test_a_shadow_lost_frames_and_a_reset_are_no_duplicate(
    model: SwarmTracker, clock: ManualClock
) -> None:
    # Light that jumps and comes back (a hand over the swarm), frame numbers with gaps (lost
    # frames) and round the 8-bit wrap, then a reset that starts them again from 0.
    for step, (seq, intensity) in enumerate(((250, 900), (255, 400), (3, 900), (40, 890))):
        clock.advance(2.0)
        hear(
            model,
            clock,
            status_frame(5, seq=seq, uptime_ms=60_000 + 2000 * step, intensity=intensity),
        )
    clock.advance(2.0)
    hear(model, clock, status_frame(5, seq=0, uptime_ms=900, resets=2))
    assert model.rows()[0].duplicate is None
    assert "Particle 5 reset" in model.notes[-1].text
