"""Commands and reports of a native particle: sensors, settings, ids, PING, IDENTIFY, STATUS."""

from __future__ import annotations

import itertools

import pytest

from particlebot.firmware.native import EEPROM_SIZE, NativeParticle
from particlebot.protocol import (
    BROADCAST_ID,
    DEFINITION_HASH,
    PARAM_SPECS,
    UNASSIGNED_ID,
    Frame,
    GetParam,
    Identify,
    Param,
    ParamResult,
    ParamValue,
    Ping,
    SetId,
    Start,
    State,
    Status,
)
from tests.firmware.conftest import Bench

R_MIN = PARAM_SPECS[Param.RADIUS_MIN_UM].default
R_MAX = PARAM_SPECS[Param.RADIUS_MAX_UM].default


def statuses(frames: list[Frame]) -> list[Status]:
    return [f.message for f in frames if isinstance(f.message, Status)]


def test_stuck_sensors_are_flagged_and_left_out_of_the_intensity(bench: Bench) -> None:
    bench.particle.set_adc([600, 0, 620, 1023, 640, 660])
    bench.advance(100)
    status = bench.status()
    assert status.sensor_faults == 0b001010
    assert status.sensors == (600, 0, 620, 1023, 640, 660)
    assert status.intensity == round((600 + 620 + 640 + 660) / 4)
    bench.particle.set_adc([0, 0, 1023, 1023, 0, 1023])
    bench.advance(100)
    assert (bench.status().sensor_faults, bench.status().intensity) == (0b111111, 0)


def test_a_blank_eeprom_gives_the_unassigned_id_and_default_parameters(bench: Bench) -> None:
    status = bench.status()
    assert bench.particle.id == UNASSIGNED_ID
    assert (status.resets, status.last_reset_cause) == (1, 1)
    assert status.definition_hash == DEFINITION_HASH
    for param, spec in PARAM_SPECS.items():
        bench.collect()
        bench.send(GetParam(target=bench.particle.id, param=param))
        (reply,) = [f.message for f in bench.collect() if isinstance(f.message, ParamValue)]
        assert (reply.param, reply.result, reply.value) == (param, ParamResult.OK, spec.default)


def test_settings_and_id_persist_in_the_eeprom_image(bench: Bench) -> None:
    assert bench.set_param(Param.CYCLE_STEPS, 75).result == ParamResult.OK
    assert bench.set_param(Param.COUNT_TOLERANCE, 25).result == ParamResult.OK
    bench.send(SetId(target=UNASSIGNED_ID, new_id=17))
    image = bench.particle.eeprom()
    assert len(image) == EEPROM_SIZE
    with NativeParticle(eeprom=image, reset_cause=8, rng_seed=3) as reborn:
        again = Bench(reborn)
        assert reborn.id == 17
        assert again.set_param(Param.CYCLE_STEPS, 75, target=17).value == 75
        status = again.status()
        assert (status.resets, status.last_reset_cause) == (2, 8)
        again.send(GetParam(target=17, param=Param.COUNT_TOLERANCE))
        replies = [f.message for f in again.collect() if isinstance(f.message, ParamValue)]
        assert [r.value for r in replies] == [25]


def test_a_corrupt_eeprom_falls_back_to_the_defaults(bench: Bench) -> None:
    bench.send(SetId(target=UNASSIGNED_ID, new_id=9))
    before = bench.particle.eeprom()
    assert bench.set_param(Param.CYCLE_STEPS, 300).result == ParamResult.OK
    image = bytearray(bench.particle.eeprom())
    changed = [i for i, (a, b) in enumerate(zip(before, image, strict=True)) if a != b]
    assert changed  # the value (and its checksum) were stored
    image[changed[0]] ^= 0x10  # one bit flips in the stored value
    with NativeParticle(eeprom=bytes(image)) as reborn:
        assert reborn.id == UNASSIGNED_ID
        assert Bench(reborn).set_param(Param.CYCLE_STEPS, 150).value == 150


def test_set_param_reports_unknown_out_of_range_and_busy(bench: Bench) -> None:
    applied = bench.set_param(Param.CYCLE_STEPS, 10)
    assert applied.result == ParamResult.OK
    low = PARAM_SPECS[Param.CYCLE_STEPS].min - 1
    refused = bench.set_param(Param.CYCLE_STEPS, low)
    assert (refused.result, refused.value) == (ParamResult.OUT_OF_RANGE, 10)
    bench.send(GetParam(target=bench.particle.id, param=99))
    (reply,) = [f.message for f in bench.collect() if isinstance(f.message, ParamValue)]
    assert reply.result == ParamResult.UNKNOWN_PARAM
    bench.send(
        Start(run_id=1, method=3, cycle_steps=0, wave_size=0, update_interval_s=0, phototaxis=0)
    )
    busy = bench.set_param(Param.CYCLE_STEPS, 20)
    assert (busy.result, busy.value) == (ParamResult.BUSY, 10)
    non_monotonic = Bench().set_param(Param.SERVO_CAL_3, 2000)  # inside its 500..2500
    assert non_monotonic.result == ParamResult.SERVO_TABLE_NOT_MONOTONIC
    crossed = Bench().set_param(Param.RADIUS_MIN_UM, PARAM_SPECS[Param.RADIUS_MAX_UM].default)
    assert crossed.result == ParamResult.RADIUS_MIN_NOT_BELOW_MAX


def test_set_id_renames_only_the_addressed_particle_and_it_answers_from_the_new_id(
    bench: Bench,
) -> None:
    bench.collect()
    bench.send(SetId(target=BROADCAST_ID, new_id=5))
    bench.send(SetId(target=33, new_id=5))
    assert bench.particle.id == UNASSIGNED_ID
    assert bench.collect() == []
    bench.send(SetId(target=UNASSIGNED_ID, new_id=5))
    assert bench.particle.id == 5
    (reply,) = bench.collect()
    assert reply.sender == 5 and isinstance(reply.message, Status)
    bench.send(SetId(target=5, new_id=BROADCAST_ID))  # not a valid id: kept
    assert bench.particle.id == 5


def test_ping_is_answered_at_once_when_addressed(bench: Bench) -> None:
    bench.collect()
    bench.send(Ping(target=77))
    assert bench.collect() == []
    bench.send(Ping(target=UNASSIGNED_ID))
    bench.send(Ping(target=UNASSIGNED_ID))
    replies = bench.collect()
    assert len(statuses(replies)) == 2
    assert replies[1].seq == (replies[0].seq + 1) & 0xFF
    assert all(f.sender == UNASSIGNED_ID for f in replies)


def test_a_broadcast_ping_is_answered_in_a_random_60_ms_slot(bench: Bench) -> None:
    # Every particle answering a broadcast at once would flood the base station's radio.
    assert bench.set_param(Param.STATUS_PERIOD_MS, 60000).result == ParamResult.OK
    bench.advance(2100)  # the periodic STATUS drawn at boot is out; the next is 45 s away
    delays = []
    for _ in range(30):
        bench.collect()
        bench.send(Ping(target=BROADCAST_ID))
        asked = bench.now
        bench.particle.tick(bench.now)
        bench.wait_for(lambda: bool(statuses(bench.collect())), 1000)
        delays.append(bench.now - asked)
    assert all(d % 60 == 0 and 0 <= d < 600 for d in delays), delays
    assert len(set(delays)) >= 6, delays  # ten slots, none favoured


def test_identify_wiggles_an_idle_particle_three_times_then_idles(bench: Bench) -> None:
    bench.collect()
    bench.send(Identify(target=bench.particle.id))
    assert statuses(bench.collect())[0].state == State.IDENTIFYING
    trace: list[int] = []
    bench.advance(1600, each=lambda t: trace.append(bench.particle.radius_um))
    assert bench.status().state == State.IDLE
    assert max(trace) <= R_MIN + (R_MAX - R_MIN) // 4
    bumps = sum(1 for a, b in itertools.pairwise(trace) if a == R_MIN < b)
    assert bumps == 3
    assert trace[-1] == R_MIN


def test_identify_does_not_move_a_running_particle(bench: Bench) -> None:
    bench.send(
        Start(run_id=1, method=3, cycle_steps=0, wave_size=0, update_interval_s=0, phototaxis=0)
    )
    bench.collect()
    bench.send(Identify(target=bench.particle.id))
    (status,) = statuses(bench.collect())
    assert status.state == State.ESTIMATING


def test_status_goes_out_every_period_with_a_quarter_of_jitter(bench: Bench) -> None:
    period = PARAM_SPECS[Param.STATUS_PERIOD_MS].default
    bench.advance(12 * period, step_ms=5, each=lambda t: bench.collect())
    times = [t for t, _ in bench.messages(Status)]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    assert len(gaps) >= 9
    assert all(0.75 * period <= g <= 1.25 * period + 5 for g in gaps)
    assert len(set(gaps)) > 1  # jittered, not a fixed beat
    seqs = [f.seq for _, f in bench.frames if isinstance(f.message, Status)]
    assert all((b - a) & 0xFF == 1 for a, b in itertools.pairwise(seqs))


@pytest.mark.parametrize("seed", [1, 2])
def test_uptime_and_counters_are_reported(seed: int) -> None:
    with NativeParticle(rng_seed=seed) as particle:
        b = Bench(particle)
        b.particle.receive(b"\x00\x01garbage")
        b.advance(500)
        status = b.status()
        assert status.uptime_ms == 600
        assert status.rx_skipped_bytes == 9
