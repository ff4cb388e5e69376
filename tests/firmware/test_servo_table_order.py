"""The servo calibration's write order against the firmware itself: every SET_PARAM of a new
table is accepted (the firmware checks each intermediate table), whichever way the tables run."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.calibration.servo import POINTS, TABLE_PARAMS, write_order
from particlebot.firmware.native import NativeParticle
from particlebot.protocol import GetParam, ParamResult, ParamValue
from tests.firmware.conftest import Bench


def tables() -> st.SearchStrategy[list[int]]:
    pulses = st.lists(st.integers(500, 2500), min_size=POINTS, max_size=POINTS)
    return st.tuples(pulses, st.booleans()).map(lambda pair: sorted(pair[0], reverse=pair[1]))


def table_of(bench: Bench) -> list[int]:
    values = []
    for param in TABLE_PARAMS:
        bench.collect()
        bench.send(GetParam(target=bench.particle.id, param=param))
        (reply,) = [f.message for f in bench.collect() if isinstance(f.message, ParamValue)]
        values.append(reply.value)
    return values


@settings(max_examples=60, deadline=None)
@given(first=tables(), second=tables())
def test_the_firmware_accepts_every_set_of_the_write_order(
    first: list[int], second: list[int]
) -> None:
    with NativeParticle(rng_seed=7) as particle:
        bench = Bench(particle)
        for old, new in ((table_of(bench), first), (first, second)):
            for point, pulse in write_order(old, new):
                answer = bench.set_param(TABLE_PARAMS[point], pulse)
                assert answer.result == ParamResult.OK, (old, new, point, pulse)
            assert table_of(bench) == new
