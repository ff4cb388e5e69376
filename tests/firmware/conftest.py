"""A light field after SI eq. 11 and a bench that drives one native particle like a base station."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import TypeVar

import pytest

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import (
    BASE_STATION_ID,
    Frame,
    Message,
    Param,
    ParamValue,
    SetParam,
    Status,
    StreamDecoder,
    encode_frame,
)

# The SI's photocell circuit and calibration (section S3): 1.5 MOhm load, V_x = 980 at r_x = 28 cm.
LOAD_OHM = 1.5e6
REF_VALUE = 980
REF_DISTANCE_M = 0.28
LAMP_HEIGHT_M = 0.28
REF_OHM = (1023 - REF_VALUE) * LOAD_OHM / REF_VALUE  # eq. 13
DIAMETER_M = 0.155
STEP_MS = 20

M = TypeVar("M", bound=Message)


def reading_at(distance_m: float) -> int:
    """Eq. 11: the 10-bit reading of a photocell distance_m from the lamp (gamma = 1)."""
    resistance = (distance_m / REF_DISTANCE_M) ** 2 * REF_OHM
    return round(1023 * LOAD_OHM / (resistance + LOAD_OHM))


def reading_on_floor(ground_m: float) -> int:
    """Reading of a particle ground_m along the floor from the point under the lamp."""
    return reading_at(math.hypot(ground_m, LAMP_HEIGHT_M))


def eq4_radius_um(k: int, steps: int, r_min: int, r_max: int) -> float:
    """Eq. 4 at step k of a cycle of `steps` servo steps.

    R(t) = dR/2 (1 + sin(2 pi f t - pi/2)) + R_min, with t = k * 20 ms and f = 1 / T.
    """
    t = k * STEP_MS / 1000
    f = 1 / (steps * STEP_MS / 1000)
    return (r_max - r_min) / 2 * (1 + math.sin(2 * math.pi * f * t - math.pi / 2)) + r_min


class Bench:
    """One particle and a base station on a wire: sends frames, ticks time, collects replies."""

    def __init__(self, particle: NativeParticle | None = None, adc: int = 600) -> None:
        self.particle = particle if particle is not None else NativeParticle(rng_seed=12345)
        self.now = 0
        self.seq = 0
        self.decoder = StreamDecoder()
        self.frames: list[tuple[int, Frame]] = []
        self.particle.set_adc([adc] * 6)
        self.advance(100)

    def send(self, message: Message, sender: int = BASE_STATION_ID) -> None:
        self.particle.receive(encode_frame(message, sender=sender, seq=self.seq & 0xFF))
        self.seq += 1

    def collect(self) -> list[Frame]:
        """Frames the particle sent since the last call, also kept in self.frames."""
        new = self.decoder.feed(self.particle.transmit())
        self.frames.extend((self.now, f) for f in new)
        return new

    def advance(
        self, ms: int, step_ms: int = 1, each: Callable[[int], object] | None = None
    ) -> None:
        """Advances ms milliseconds in ticks of step_ms, calling each(now) after every tick."""
        end = self.now + ms
        while self.now < end:
            self.now = min(self.now + step_ms, end)
            self.particle.tick(self.now)
            if each is not None:
                each(self.now)
        self.collect()

    def wait_for(self, condition: Callable[[], bool], timeout_ms: int, step_ms: int = 1) -> int:
        """Ticks until condition() holds; returns that time, fails after timeout_ms."""
        end = self.now + timeout_ms
        while not condition():
            if self.now >= end:
                raise AssertionError(f"condition not met within {timeout_ms} ms")
            self.now += step_ms
            self.particle.tick(self.now)
        self.collect()
        return self.now

    def status(self) -> Status:
        return self.particle.status()

    def messages(self, kind: type[M]) -> list[tuple[int, M]]:
        """(time collected, message) of every frame of that kind seen so far."""
        return [(t, f.message) for t, f in self.frames if isinstance(f.message, kind)]

    def set_param(self, param: Param, value: int, target: int | None = None) -> ParamValue:
        """SET_PARAM addressed to the particle's own id (answered at once, not in a reply slot)."""
        self.collect()
        own = self.particle.id if target is None else target
        self.send(SetParam(target=own, param=param, value=value))
        replies = [f.message for f in self.collect() if isinstance(f.message, ParamValue)]
        assert len(replies) == 1, replies
        return replies[0]


@pytest.fixture
def bench() -> Iterator[Bench]:
    b = Bench()
    yield b
    b.particle.close()
