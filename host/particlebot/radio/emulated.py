"""A base-station radio on emulated air with simavr particles running the real firmware image.

emulated://K?loss=0.2&delay_ms=5&speed=1&spacing=0.155&start=0.10&lamp=X,Y,H&seed=1&elf=PATH
&base_baud=9600&buffer=256&scenario=line&photocell_spread=0.1:
K particles (ids 1..K) in a line from the lamp, each the ELF that
`make firmware` builds, in tools/sim/particle_sim (`make harness`), on 802.15.4 air as
particlebot.sim.medium models it. speed=max runs as fast as the machine allows.
"""

from __future__ import annotations

from pathlib import Path
from typing import Self

from particlebot.options import NON_NEGATIVE, POSITIVE, Bounds
from particlebot.radio import RadioError, RadioUrl
from particlebot.radio._simulated import (
    SwarmRadio,
    parse_count,
    parse_lamp,
    parse_photocell_spread,
)
from particlebot.radio.faults import (
    FAULT_OPTIONS,
    SIMULATION_OPTIONS,
    faults_from_url,
    scenario_from_url,
)
from particlebot.sim.harness import HarnessError
from particlebot.sim.swarm import EmulatedSwarm, SwarmConfig

OPTIONS = {
    "speed",
    "spacing",
    "start",
    "lamp",
    "elf",
    "base_baud",
    "buffer",
    "photocell_spread",
    *FAULT_OPTIONS,
    *SIMULATION_OPTIONS,
}
MAX_PARTICLES = 32
"""One harness process each; the firmware records at most 32 senders per round anyway."""


def swarm_config_from_url(url: RadioUrl) -> SwarmConfig:
    url.check_options(OPTIONS)
    scenario_from_url(url)
    faults = faults_from_url(url)
    elf = Path(url.options["elf"]) if "elf" in url.options else None
    return SwarmConfig(
        count=parse_count(url, default=5, maximum=MAX_PARTICLES),
        lamp=parse_lamp(url),
        start=url.get_float("start", 0.10, NON_NEGATIVE),
        spacing=url.get_float("spacing", 0.155, POSITIVE),
        loss=faults.loss,
        delay_us=faults.delay_s * 1_000_000,
        seed=url.get_int("seed", 1, NON_NEGATIVE),
        elf=elf,
        base_baud=url.get_int("base_baud", 9600, POSITIVE),
        # A whole 100-byte RF packet must fit, or the radio could never pass one on.
        buffer_bytes=url.get_int("buffer", 256, Bounds(minimum=100)),
        keep_history=False,
        photocell_spread=parse_photocell_spread(url),
    )


class EmulatedRadio(SwarmRadio[EmulatedSwarm]):
    """The base station's radio on an EmulatedSwarm's air."""

    restart_advice = "rebuild with `make firmware harness` and open it again"

    def __init__(
        self,
        swarm: EmulatedSwarm,
        *,
        url: str = "emulated://",
        speed: float | None = None,
        owns_swarm: bool = False,
    ) -> None:
        """speed: step the swarm on its own thread at this pace (else the caller steps it).
        owns_swarm: close() ends the particles' processes too."""
        self._owns_swarm = owns_swarm
        super().__init__(swarm, url=url, speed=speed)

    def _connect(self) -> None:
        self.swarm.add_base_listener(self._deliver)

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        config = swarm_config_from_url(url)
        speed = url.get_speed()  # checked either way
        pace = None if url.caller_steps else speed
        try:
            swarm = EmulatedSwarm(config)
        except (FileNotFoundError, HarnessError, OSError) as exc:
            raise RadioError(
                f"The emulated particles need the firmware image and the simavr harness ({exc}). "
                "Run: make firmware harness (after `make system-deps` for the AVR tools)"
            ) from exc
        return cls(swarm, url=url.text, speed=pace, owns_swarm=True)

    def close(self) -> None:
        if self._owns_swarm:
            self.swarm.close()  # its thread first, then the particles' processes
        super().close()
