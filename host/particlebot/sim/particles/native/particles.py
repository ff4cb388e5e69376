"""Native particles: one NativeParticle (the firmware's Particle class, through ctypes) each, fed
and read the way main.cpp feeds and reads it on the chip."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol

import numpy as np

from particlebot.firmware.native import (
    NativeBatch,
    NativeParticle,
    firmware_constants,
    settings_image,
)
from particlebot.protocol import Param
from particlebot.sim.air.medium import BITS_PER_CHAR, Reception, SerialLine
from particlebot.sim.clock import CPU_HZ, CYCLES_PER_MS
from particlebot.sim.particles.interface import FirmwareParticles, FloatArray, SerialByte

TICK_MS = 5
"""The logic is ticked every 5 ms: the C API's servo steps land on their 20 ms boundaries when it
is ticked at least that often. A byte from the radio reaches it at the first tick after the
byte is in (at most 5 ms late)."""
TICK_CYCLES = TICK_MS * CYCLES_PER_MS
POWER_ON = 1
"""MCUSR's power-on flag: what a particle switched on reports as its reset cause."""


class FirmwareParticle(Protocol):
    """What the swarm needs of particlebot.firmware.native.NativeParticle."""

    def set_adc(self, values: list[int]) -> None: ...

    def receive(self, data: bytes) -> None: ...

    def tick(self, now_ms: int) -> None: ...

    def transmit_frame(self) -> bytes: ...

    @property
    def id(self) -> int: ...

    @property
    def radius_um(self) -> int: ...

    def close(self) -> None: ...


ParticleFactory = Callable[[bytes, int], FirmwareParticle]
"""factory(eeprom, rng_seed) -> a particle booted from that EEPROM image."""


def native_factory(eeprom: bytes, seed: int) -> FirmwareParticle:
    # Imported here: the module is importable without the native library built.
    from particlebot.firmware.native import NativeParticle

    particle: FirmwareParticle = NativeParticle(eeprom=eeprom, reset_cause=POWER_ON, rng_seed=seed)
    return particle


class NativeParticles(FirmwareParticles):
    """K particles of the firmware logic, each booted from an EEPROM that holds its id.

    As main.cpp does, each particle hands its radio one whole frame at a time and then keeps its
    serial line quiet for the firmware's inter-frame gap, so that its XBee sends every frame as an
    RF packet of its own; the bytes leave at 9600 baud (sim.air.SerialLine).
    """

    level = "native"
    exact_air = False

    def __init__(
        self,
        ids: Sequence[int],
        *,
        params: Mapping[Param, int] | None = None,
        seed: int = 1,
        factory: ParticleFactory = native_factory,
    ) -> None:
        super().__init__(ids)
        constants = firmware_constants()
        self._gap_cycles = constants.inter_frame_gap_ms * CYCLES_PER_MS
        self.firmware: list[FirmwareParticle] = []
        try:
            for index, particle_id in enumerate(self.ids):
                image = settings_image(particle_id, params)
                self.firmware.append(factory(image, seed * 1000 + index))
        except BaseException:
            self.close()
            raise
        self._lines = [SerialLine() for _ in self.ids]
        self._quiet_until = [0] * self.count
        self._inbox: list[deque[tuple[int, bytes]]] = [deque() for _ in self.ids]
        self._busy: set[int] = set()
        """Particles with bytes from their radio still to take."""
        self._next_tick = 0
        self._radii = np.array([p.radius_um for p in self.firmware], dtype=np.float64) * 1e-6
        # The firmware logic itself (not a stand-in of a test): all ticked in one call.
        self._batch = (
            NativeBatch(self.firmware)  # type: ignore[arg-type]
            if all(type(p) is NativeParticle for p in self.firmware)
            else None
        )

    def node_name(self, index: int) -> str:
        return f"virtual-{index + 1:02d}"

    def next_stop(self, cycle: int) -> int:
        return max(self._next_tick, cycle + 1)

    def run_until(self, cycle: int) -> list[SerialByte]:
        out: list[SerialByte] = []
        while self._next_tick <= cycle:
            now = self._next_tick
            now_ms = (now // CYCLES_PER_MS) & 0xFFFFFFFF
            if self._batch is not None:
                self._batch.tick(now_ms)
                waiting = self._batch.tx_waiting
                speakers = {i for i in range(self.count) if waiting[i]}
            else:
                for particle in self.firmware:
                    particle.tick(now_ms)
                speakers = set(range(self.count))
            for index in list(self._busy):
                inbox = self._inbox[index]
                while inbox and inbox[0][0] <= now:
                    self.firmware[index].receive(inbox.popleft()[1])
                    speakers.add(index)  # a command may be answered at once
                if not inbox:
                    self._busy.discard(index)
            for index in sorted(speakers):
                if now >= self._quiet_until[index]:
                    self._send(index, now, out)
            self._next_tick = now + TICK_CYCLES
        return out

    def _send(self, index: int, now: int, out: list[SerialByte]) -> None:
        frame = self.firmware[index].transmit_frame()
        if frame:
            ends = self._lines[index].write(frame, now)
            out.extend(SerialByte(index, c, v) for c, v in zip(ends, frame, strict=True))
            self._quiet_until[index] = ends[-1] + self._gap_cycles

    def receive(self, copy: Reception) -> None:
        inbox = self._inbox[copy.receiver]
        self._busy.add(copy.receiver)
        data = copy.data
        # Bytes reach the logic at the first tick after each is in, grouped by that tick. Byte i
        # is in at ceil((line_start + (i + 1) C) / baud) with C = 10 CPU_HZ (sim.clock), so the
        # bytes in by cycle b are the first floor((b baud - line_start) / C).
        start_scaled, baud = copy.line_start, copy.baud
        char_scaled = BITS_PER_CHAR * CPU_HZ
        first_end = (start_scaled + char_scaled + baud - 1) // baud
        tick = -(-first_end // TICK_CYCLES) * TICK_CYCLES
        taken = 0
        while taken < len(data):
            count = min(len(data), (tick * baud - start_scaled) // char_scaled)
            if count > taken:
                inbox.append((tick, data[taken:count]))
                taken = count
            tick += TICK_CYCLES

    def set_light(self, index: int, readings: Sequence[int]) -> None:
        self.firmware[index].set_adc([int(v) for v in readings])

    def radii_m(self) -> FloatArray:
        if self._batch is not None:
            micrometres = np.frombuffer(memoryview(self._batch.radius_um), dtype=np.uint32)
            return np.asarray(micrometres * 1e-6, dtype=np.float64)
        radii = self._radii
        for index, particle in enumerate(self.firmware):
            radii[index] = particle.radius_um * 1e-6
        return radii.copy()

    def close(self) -> None:
        for particle in self.firmware:
            particle.close()
        self.firmware = []
