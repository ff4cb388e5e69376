"""Emulated particles: one simavr harness process per particle running the flashed image, stepped
in lockstep; its photocells are voltages, its radius what its servo pulses give."""

from __future__ import annotations

import statistics
from collections import deque
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from particlebot.firmware.native import settings_image
from particlebot.protocol import PARAM_SPECS, Param
from particlebot.sim.air.medium import Reception
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.harness import ParticleSim, default_elf
from particlebot.sim.particles.emulated.servo import default_servo_table, servo_radius_um
from particlebot.sim.particles.interface import FirmwareParticles, FloatArray, SerialByte
from particlebot.sim.world.light import ADC_FULL_SCALE

AVCC_MV = 3300
"""The Fio v3 runs at 3.3 V: a full-scale reading is 3300 mV at the ADC pin."""
MAX_QUANTUM_US = 3000
"""A particle's byte needs RO (3 characters) of silence plus its airtime before anyone can hear
it; steps shorter than that let no effect reach another particle within the same step."""


def light_to_millivolts(value: float) -> int:
    """The divider voltage that makes an eq. 11 reading of value (on a 1023 scale) at 3.3 V."""
    return round(min(max(value, 0.0), ADC_FULL_SCALE) * AVCC_MV / ADC_FULL_SCALE)


def node_name(index: int) -> str:
    """The emulated XBee's 64-bit address (Digi's OUI, then the particle's number)."""
    return f"0013A200{index + 1:08X}"


def _param(params: Mapping[Param, int], param: Param) -> int:
    return params.get(param, PARAM_SPECS[param].default)


class EmulatedParticles(FirmwareParticles):
    """K particle_sim processes, each the image `make firmware` builds (or the fault-injection
    build for the indices in fault_elf), booted from an EEPROM that holds its id and params.

    Their servo is the one their calibration table describes (servo.servo_radius_um): the body
    follows the latest pulse on D9, one 20 ms frame at a time.
    """

    level = "emulated"
    exact_air = True

    def __init__(
        self,
        ids: Sequence[int],
        *,
        params: Mapping[Param, int] | None = None,
        seed: int = 1,
        quantum_us: float = 2000.0,
        elf: Path | None = None,
        fault_elf: Sequence[int] = (),
        harness: Path | None = None,
        keep_history: bool = True,
    ) -> None:
        super().__init__(ids)
        if not 0 < quantum_us <= MAX_QUANTUM_US:
            raise ValueError(f"quantum_us must be in (0, {MAX_QUANTUM_US}]")
        params = dict(params or {})
        self.keep_history = keep_history
        self._quantum = round(quantum_us * CPU_HZ / 1_000_000)
        self._seen: list[int] = []
        self.sims: list[ParticleSim] = []
        # The servo in the particle: its true curve is the table the particle starts with.
        points = len(default_servo_table())
        self._servo_table = [
            _param(params, Param(int(Param.SERVO_CAL_0) + k)) for k in range(points)
        ]
        self._r_min_um = _param(params, Param.RADIUS_MIN_UM)
        self._r_max_um = _param(params, Param.RADIUS_MAX_UM)
        self._radii = np.full(self.count, self._r_min_um * 1e-6)
        self._recent: list[deque[float]] = [deque(maxlen=3) for _ in self.ids]
        self._pulses_seen = [0] * self.count
        try:
            for index, particle_id in enumerate(self.ids):
                image = elf if index not in fault_elf else default_elf(faults=True)
                self.sims.append(
                    ParticleSim(
                        image,
                        harness=harness,
                        eeprom=settings_image(particle_id, params),
                        # The firmware seeds its random numbers from this: every particle differs.
                        noise_mv=250 + (seed * 37 + index * 11) % 200,
                    )
                )
                self._seen.append(0)
        except BaseException:
            self.close()
            raise

    def node_name(self, index: int) -> str:
        return node_name(index)

    def next_stop(self, cycle: int) -> int:
        return cycle + self._quantum

    def run_until(self, cycle: int) -> list[SerialByte]:
        for sim in self.sims:
            sim.begin_run(cycle)
        for sim in self.sims:
            sim.finish_run()
        out: list[SerialByte] = []
        for index, sim in enumerate(self.sims):
            out.extend(SerialByte(index, b.cycle, b.value) for b in sim.uart[self._seen[index] :])
            if sim.servo_pulses:
                recent = self._recent[index]
                recent.extend(p.width_us for p in sim.servo_pulses[self._pulses_seen[index] :])
                self._pulses_seen[index] = len(sim.servo_pulses)
                # A servo's mechanics follow the pulses over several frames, not a lone edge
                # that came late behind another interrupt: the median of the last three.
                width = statistics.median(recent)
                radius = servo_radius_um(width, self._servo_table, self._r_min_um, self._r_max_um)
                self._radii[index] = radius * 1e-6
            if self.keep_history:
                self._seen[index] = len(sim.uart)
            else:
                sim.forget()
                self._pulses_seen[index] = 0
        return out

    def receive(self, copy: Reception) -> None:
        # The harness paces the bytes itself, as the radio's serial line does, from now on.
        self.sims[copy.receiver].send_uart(copy.data)

    def set_light(self, index: int, readings: Sequence[int]) -> None:
        self.sims[index].set_light_mv([light_to_millivolts(v) for v in readings])

    def radii_m(self) -> FloatArray:
        return self._radii.copy()

    def close(self) -> None:
        for sim in self.sims:
            sim.close()
