"""A few native particles wired together: they rank themselves by light and move in a wave."""

from __future__ import annotations

import pytest

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import (
    BASE_STATION_ID,
    PARAM_SPECS,
    UNASSIGNED_ID,
    Method,
    Param,
    SetId,
    SetParam,
    Start,
    StreamDecoder,
    encode_frame,
)
from tests.firmware.conftest import DIAMETER_M, reading_on_floor

R_MIN = PARAM_SPECS[Param.RADIUS_MIN_UM].default
ROUND_MS = 600
TICK_MS = 5


class Wire:
    """Every byte one particle sends reaches all the others (and the base) at once."""

    def __init__(self, ground_m: list[float]) -> None:
        self.particles = [NativeParticle(rng_seed=100 + i) for i in range(len(ground_m))]
        self.now = 0
        self.seq = 0
        self.base = StreamDecoder()
        for i, (p, ground) in enumerate(zip(self.particles, ground_m, strict=True)):
            p.set_adc([reading_on_floor(ground)] * 6)
            p.receive(encode_frame(SetId(target=UNASSIGNED_ID, new_id=i + 1), BASE_STATION_ID, 0))
        self.broadcast(SetParam(target=255, param=Param.ROUND_MS, value=ROUND_MS))
        self.run(100)

    def broadcast(self, message: SetParam | Start) -> None:
        frame = encode_frame(message, BASE_STATION_ID, self.seq & 0xFF)
        self.seq += 1
        for p in self.particles:
            p.receive(frame)

    def run(self, ms: int, each: object = None) -> None:
        end = self.now + ms
        while self.now < end:
            self.now += TICK_MS
            for p in self.particles:
                p.tick(self.now)
            for sender in self.particles:
                data = sender.transmit()
                if data:
                    self.base.feed(data)
                    for p in self.particles:
                        if p is not sender:
                            p.receive(data)
            if callable(each):
                each(self.now)

    def close(self) -> None:
        for p in self.particles:
            p.close()


@pytest.fixture
def line() -> object:
    # Five particles in a row from under the lamp, touching (one contracted diameter apart),
    # listed out of order so nothing depends on the order of the list.
    order = [3, 0, 4, 1, 2]
    wire = Wire([k * DIAMETER_M for k in order])
    wire.ranks = [k + 1 for k in order]  # type: ignore[attr-defined]
    yield wire
    wire.close()


def test_counting_gives_every_particle_its_rank_by_distance(line: Wire) -> None:
    readings = [p.status().intensity for p in line.particles]
    assert len(set(readings)) == len(readings)
    assert min(abs(a - b) for a in readings for b in readings if a != b) > 10  # distinct levels
    line.broadcast(
        Start(
            run_id=1,
            method=Method.COUNTING,
            cycle_steps=50,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    line.run(ROUND_MS + 50)
    statuses = [p.status() for p in line.particles]
    assert [s.s_n for s in statuses] == line.ranks  # type: ignore[attr-defined]
    assert all(s.group_size == 5 for s in statuses)


def test_the_group_moves_in_a_wave_from_the_particle_nearest_the_light(line: Wire) -> None:
    cycle_steps = 50
    period = cycle_steps * 20
    first_move: dict[int, int] = {}

    def watch(now: int) -> None:
        for i, p in enumerate(line.particles):
            if i not in first_move and p.radius_um > R_MIN:
                first_move[i] = now

    t0 = line.now
    line.broadcast(
        Start(
            run_id=2,
            method=Method.COUNTING,
            cycle_steps=cycle_steps,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    line.run(ROUND_MS + 3 * period, each=watch)
    for i, rank in enumerate(line.ranks):  # type: ignore[attr-defined]
        scheduled = t0 + ROUND_MS + (rank - 1) * period // 2
        assert scheduled < first_move[i] <= scheduled + 20 + TICK_MS


def test_direct_estimation_agrees_with_counting_on_a_line(line: Wire) -> None:
    line.broadcast(
        Start(
            run_id=3,
            method=Method.DIRECT,
            cycle_steps=50,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    line.run(ROUND_MS + 50)
    assert [p.status().s_n for p in line.particles] == line.ranks  # type: ignore[attr-defined]
