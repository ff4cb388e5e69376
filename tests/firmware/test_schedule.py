"""The run schedule end to end: t_I, eq. 4 cycles, pauses, epochs, phototaxis and STOP."""

from __future__ import annotations

import itertools
import math

import pytest

from particlebot.protocol import (
    BROADCAST_ID,
    PARAM_SPECS,
    Identify,
    Intensity,
    Method,
    Param,
    ParamResult,
    Ping,
    ServoHold,
    Start,
    State,
    Status,
    Stop,
)
from tests.firmware.conftest import DIAMETER_M, STEP_MS, Bench, eq4_radius_um, reading_on_floor

R_MIN = PARAM_SPECS[Param.RADIUS_MIN_UM].default
R_MAX = PARAM_SPECS[Param.RADIUS_MAX_UM].default
ROUND_MS = PARAM_SPECS[Param.ROUND_MS].default
STOP_RAMP_FULL_MS = 600


def start(
    bench: Bench,
    run_id: int = 1,
    method: Method = Method.COUNTING,
    cycle_steps: int = 150,
    wave_size: int = 1,
    update_interval_s: int = 0,
    phototaxis: int = 0,
) -> int:
    """Sends START now and returns its time (the start of the estimation round)."""
    bench.send(
        Start(
            run_id=run_id,
            method=method,
            cycle_steps=cycle_steps,
            wave_size=wave_size,
            update_interval_s=update_interval_s,
            phototaxis=phototaxis,
        )
    )
    return bench.now


def radii(bench: Bench, ms: int) -> dict[int, int]:
    """The commanded radius after every millisecond tick for the next ms milliseconds."""
    seen: dict[int, int] = {}
    bench.advance(ms, each=lambda t: seen.__setitem__(t, bench.particle.radius_um))
    return seen


def expansion_starts(trace: dict[int, int]) -> list[int]:
    """Times at which the radius leaves R_min."""
    times = sorted(trace)
    return [t for prev, t in itertools.pairwise(times) if trace[prev] == R_MIN < trace[t]]


@pytest.mark.parametrize("rank", [1, 2, 3, 5])
def test_first_expansion_starts_half_a_period_per_rank_after_the_common_start(
    bench: Bench, rank: int
) -> None:
    bench.particle.set_adc([reading_on_floor((rank - 1) * DIAMETER_M)] * 6)
    bench.advance(100)
    t0 = start(bench, method=Method.DIRECT, cycle_steps=150, wave_size=5)
    period = 150 * STEP_MS
    scheduled = t0 + ROUND_MS + (rank - 1) * period // 2  # eq. 5 after the common start
    trace = radii(bench, scheduled - t0 + period)
    assert bench.status().s_n == rank
    first = expansion_starts(trace)[0]
    assert scheduled < first <= scheduled + STEP_MS
    assert all(r == R_MIN for t, r in trace.items() if t < scheduled)


@pytest.mark.parametrize("cycle_steps", [75, 150, 300])
def test_a_cycle_follows_eq_4_each_step_and_repeats_after_t_p(
    bench: Bench, cycle_steps: int
) -> None:
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    t0 = start(bench, cycle_steps=cycle_steps, wave_size=3)
    period = cycle_steps * STEP_MS
    pause = (3 - 1) * period // 2  # eq. 3 with N = 3
    cycle_start = t0 + 200
    trace = radii(bench, 200 + 2 * period + pause + 100)
    for t in range(cycle_start, cycle_start + period):
        k = (t - cycle_start) // STEP_MS
        assert abs(trace[t] - eq4_radius_um(k, cycle_steps, R_MIN, R_MAX)) <= 1, t
    # Contracted for the whole pause, then the same cycle again.
    assert all(trace[t] == R_MIN for t in range(cycle_start + period, cycle_start + period + pause))
    starts = expansion_starts(trace)
    assert [s - starts[0] for s in starts[:2]] == [0, period + pause]
    peak = max(trace.values())
    assert (
        abs(peak - max(eq4_radius_um(k, cycle_steps, R_MIN, R_MAX) for k in range(cycle_steps)))
        <= 1
    )
    assert list(trace.values()).count(peak) >= STEP_MS  # each step's radius is held for 20 ms


def test_a_start_that_leaves_cycle_and_interval_out_keeps_the_stored_ones(bench: Bench) -> None:
    # The console's `s` then Enter sends 0 for both: `set cycle_steps 76` must still hold.
    assert bench.set_param(Param.CYCLE_STEPS, 76).result == ParamResult.OK
    assert bench.set_param(Param.UPDATE_INTERVAL_S, 10).result == ParamResult.OK
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    t0 = start(bench, cycle_steps=0, wave_size=1, update_interval_s=0)
    trace = radii(bench, 12_000)
    first, second = expansion_starts(trace)[:2]
    assert second - first == 76 * STEP_MS  # T of the stored 76 steps (N = 1: no pause)
    # The stored 10 s interval: the next epoch's estimation round begins at t0 + 10 s, and every
    # particle is contracted for it.
    epoch_end = t0 + 10_000
    assert all(trace[t] == R_MIN for t in range(epoch_end, epoch_end + 200))
    assert any(trace[t] > R_MIN for t in range(epoch_end - 2 * 76 * STEP_MS, epoch_end))


def test_servo_pulses_rise_with_the_radius_within_500_to_2500_us(bench: Bench) -> None:
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    start(bench, cycle_steps=76, wave_size=1)  # an even count of steps reaches R_max exactly
    pairs: set[tuple[int, int]] = set()
    bench.advance(
        200 + 1520,
        each=lambda t: pairs.add((bench.particle.radius_um, bench.particle.servo_pulse_us)),
    )
    ordered = sorted(pairs)
    pulses = [p for _, p in ordered]
    assert pulses == sorted(pulses)
    assert all(500 <= p <= 2500 for p in pulses)
    assert dict(ordered)[R_MIN] == PARAM_SPECS[Param.SERVO_CAL_0].default
    assert dict(ordered)[R_MAX] == PARAM_SPECS[Param.SERVO_CAL_8].default


def test_a_falling_calibration_table_gives_falling_pulses(bench: Bench) -> None:
    cal = [Param(Param.SERVO_CAL_0 + i) for i in range(9)]
    for p in cal[1:]:
        assert bench.set_param(p, 1000).result == ParamResult.OK
    for i, p in enumerate(cal[:-1]):
        assert bench.set_param(p, 2000 - 100 * i).result == ParamResult.OK
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    start(bench, cycle_steps=76)
    pairs: set[tuple[int, int]] = set()
    bench.advance(
        1720, each=lambda t: pairs.add((bench.particle.radius_um, bench.particle.servo_pulse_us))
    )
    pulses = [p for _, p in sorted(pairs)]
    assert pulses == sorted(pulses, reverse=True)
    assert pulses[0] == 2000 and pulses[-1] == 1000


def drive_to(bench: Bench, state: State) -> int:
    """Brings the particle into `state` and returns the cycle length in steps it uses."""
    if state is State.IDLE:
        return 150
    if state is State.IDENTIFYING:
        bench.send(Identify(target=BROADCAST_ID))
        bench.advance(300)
        return 150
    if state is State.HOLDING:
        bench.send(ServoHold(target=bench.particle.id, pulse_us=1900, hold_s=30))
        bench.advance(100)
        return 150
    if state is State.DONE:
        bench.set_param(Param.ROUND_MS, 200)
        start(bench, cycle_steps=10, update_interval_s=1, phototaxis=1)
        bench.advance(1100)
        bench.particle.set_adc([400] * 6)
        bench.advance(1200)
        return 10
    if state is State.ESTIMATING:
        start(bench)
        bench.advance(50)
        return 150
    if state is State.WAITING:
        bench.particle.set_adc([reading_on_floor(3 * DIAMETER_M)] * 6)
        bench.advance(100)
        start(bench, method=Method.DIRECT, wave_size=4)
        bench.advance(ROUND_MS + 500)
        return 150
    if state in (State.CYCLING, State.STOPPING):
        start(bench, cycle_steps=150)
        bench.advance(ROUND_MS + 1400)  # nearly fully expanded
        if state is State.STOPPING:
            bench.send(Stop())
            bench.advance(100)
        return 150
    if state is State.PAUSED:
        start(bench, cycle_steps=75, wave_size=3)
        bench.advance(ROUND_MS + 1500 + 200)
        return 75
    raise AssertionError(state)


@pytest.mark.parametrize("state", list(State))
def test_stop_in_every_state_contracts_smoothly_within_a_second(bench: Bench, state: State) -> None:
    cycle_steps = drive_to(bench, state)
    assert bench.status().state == state
    stop_at = bench.now
    before = bench.particle.radius_um
    bench.send(Stop())
    # At once, before the next tick; an idle particle has nothing to stop and stays IDLE, and one
    # holding its servo lets go and is IDLE (the servo returns straight to the contracted pulse).
    at_rest = state in (State.IDLE, State.HOLDING)
    assert bench.status().state == (State.IDLE if at_rest else State.STOPPING)
    trace = radii(bench, 1000)
    if before > R_MIN:
        assert trace[stop_at + STEP_MS] < before  # moving down within one servo step
    values = [before, *(trace[t] for t in sorted(trace))]
    steps = [a - b for a, b in itertools.pairwise(values)]
    assert all(s >= 0 for s in steps), "the radius rose after STOP"
    stroke = R_MAX - R_MIN
    # No step steeper than the full-stroke half-cosine ramp or the run's own sinusoid allow.
    allowed = max(
        math.pi * stroke / (2 * STOP_RAMP_FULL_MS / STEP_MS), math.pi * stroke / cycle_steps
    )
    assert max(steps) <= allowed + 1
    assert trace[stop_at + STOP_RAMP_FULL_MS] == R_MIN
    status = bench.status()
    assert status.state == State.IDLE
    assert status.radius_um == R_MIN
    assert bench.particle.servo_pulse_us == PARAM_SPECS[Param.SERVO_CAL_0].default


def test_stop_is_obeyed_within_one_step_mid_cycle(bench: Bench) -> None:
    start(bench, cycle_steps=150)
    bench.advance(ROUND_MS + 700)  # rising
    rising = bench.particle.radius_um
    bench.send(Stop())
    assert bench.status().state == State.STOPPING
    trace = radii(bench, STEP_MS)
    assert trace[bench.now] < rising


def test_intensity_is_broadcast_repeatedly_early_in_the_round(bench: Bench) -> None:
    bench.particle.set_adc([700] * 6)
    bench.advance(100)
    t0 = start(bench, run_id=9)
    bench.advance(ROUND_MS, each=lambda t: bench.collect())
    sent = bench.messages(Intensity)
    repeats = PARAM_SPECS[Param.BROADCAST_REPEATS].default
    assert [m.repeat for _, m in sent] == list(range(repeats))
    assert all(m.intensity == 700 and m.run_id == 9 and m.round == 0 for _, m in sent)
    assert all(t0 <= t <= t0 + 0.7 * ROUND_MS + 1 for t, _ in sent)


def test_direct_estimation_broadcasts_nothing(bench: Bench) -> None:
    start(bench, method=Method.DIRECT)
    bench.advance(ROUND_MS + 100)
    assert bench.messages(Intensity) == []
    assert bench.status().group_size == 1


def test_a_resent_start_of_the_same_run_is_ignored_and_a_new_run_restarts(bench: Bench) -> None:
    start(bench, run_id=4)
    bench.advance(ROUND_MS + 100)
    assert bench.status().state == State.CYCLING
    start(bench, run_id=4)
    assert bench.status().state == State.CYCLING
    start(bench, run_id=5)
    status = bench.status()
    assert (status.state, status.run_id) == (State.ESTIMATING, 5)
    trace = radii(bench, 700)
    assert trace[bench.now] == R_MIN  # ramped down during the new round


def test_every_epoch_re_estimates_and_starts_contracted(bench: Bench) -> None:
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    bench.particle.set_adc([reading_on_floor(0.0)] * 6)
    bench.advance(100)
    t0 = start(bench, method=Method.DIRECT, cycle_steps=25, wave_size=2, update_interval_s=2)
    epoch = 2000  # max(update interval, round + T + t_p + T / 2) = max(2000, 200 + 500 + 250 + 250)
    trace = radii(bench, epoch - 300)
    assert bench.status().s_n == 1
    bench.particle.set_adc([reading_on_floor(2 * DIAMETER_M)] * 6)
    trace.update(radii(bench, 2 * epoch))
    status_later = bench.status()
    assert status_later.s_n == 3
    for k in range(3):
        boundary = t0 + k * epoch
        assert all(trace[t] == R_MIN for t in range(boundary + 1, boundary + 200) if t in trace)
    second_epoch_starts = [s for s in expansion_starts(trace) if t0 + epoch <= s < t0 + 2 * epoch]
    assert second_epoch_starts[0] - STEP_MS == t0 + epoch + 200 + (3 - 1) * 250


def test_phototaxis_stops_when_the_light_no_longer_increases(bench: Bench) -> None:
    assert bench.set_param(Param.ROUND_MS, 200).result == ParamResult.OK
    bench.particle.set_adc([500] * 6)
    bench.advance(100)
    t0 = start(bench, cycle_steps=10, update_interval_s=1, phototaxis=1)
    bench.advance(900)
    bench.particle.set_adc([600] * 6)  # brighter for round 1
    bench.advance(400)
    assert bench.status().state != State.DONE
    bench.advance(t0 + 2000 + 150 - bench.now)  # round 2 reads the same: not brighter
    assert bench.status().state == State.ESTIMATING
    bench.advance(100)
    status = bench.status()
    assert status.state == State.DONE
    assert status.radius_um == R_MIN
    bench.send(Ping(target=bench.particle.id))
    assert any(isinstance(f.message, Status) for f in bench.collect())


@pytest.mark.parametrize(("rank", "wave", "cycle_steps"), [(9, 1, 300), (8, 2, 150), (6, 4, 150)])
def test_the_back_of_the_wave_cycles_every_epoch_at_the_shortest_update_interval(
    bench: Bench, rank: int, wave: int, cycle_steps: int
) -> None:
    # Eq. 5's t_I would put these first cycles past the end of a 10 s epoch, every epoch.
    interval_s = PARAM_SPECS[Param.UPDATE_INTERVAL_S].min
    bench.particle.set_adc([reading_on_floor((rank - 1) * DIAMETER_M)] * 6)
    bench.advance(100)
    t0 = start(
        bench,
        method=Method.DIRECT,
        cycle_steps=cycle_steps,
        wave_size=wave,
        update_interval_s=interval_s,
    )
    half = cycle_steps * STEP_MS // 2
    wave_period = (wave + 1) * half  # T + t_p
    epoch = max(interval_s * 1000, ROUND_MS + (wave + 2) * half)
    trace: dict[int, int] = {}
    bench.advance(
        3 * epoch, step_ms=10, each=lambda t: trace.__setitem__(t, bench.particle.radius_um)
    )
    assert bench.status().s_n == rank
    for k in range(3):
        begin = t0 + k * epoch
        common_start = begin + ROUND_MS
        starts = [s for s in expansion_starts(trace) if begin <= s < begin + epoch]
        assert starts, f"no cycle in epoch {k}"
        for s in starts:
            # The radius leaves R_min one servo step into a cycle; samples are 10 ms apart.
            since = s - STEP_MS - common_start - (rank - 1) * half
            assert 0 <= since % wave_period < 10, (k, s)
        assert trace[begin + epoch - 10] == R_MIN
