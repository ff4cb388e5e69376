"""A stand-in for a native particle that forwards everything to the real one: tests override the
one call they watch or break."""

from __future__ import annotations

from particlebot.sim.particles.native import FirmwareParticle


class Delegate:
    def __init__(self, inner: FirmwareParticle) -> None:
        self.inner = inner

    def set_adc(self, values: list[int]) -> None:
        self.inner.set_adc(values)

    def receive(self, data: bytes) -> None:
        self.inner.receive(data)

    def tick(self, now_ms: int) -> None:
        self.inner.tick(now_ms)

    def transmit_frame(self) -> bytes:
        return self.inner.transmit_frame()

    @property
    def id(self) -> int:
        return self.inner.id

    @property
    def radius_um(self) -> int:
        return self.inner.radius_um

    def close(self) -> None:
        self.inner.close()
