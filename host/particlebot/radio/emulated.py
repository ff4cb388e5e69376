"""A base-station radio on emulated air with simavr particles running the real firmware image.

emulated://K?loss=0.2&delay_ms=5&speed=1&spacing=0.155&start=0.10&lamp=X,Y,H&seed=1&elf=PATH
&base_baud=9600&buffer=256: K particles (ids 1..K) in a line from the lamp, each the ELF that
`make firmware` builds, in tools/sim/particle_sim (`make harness`), on 802.15.4 air as
particlebot.sim.medium models it. speed=max runs as fast as the machine allows.
"""

from __future__ import annotations

import math
import queue
from pathlib import Path
from typing import Self

from particlebot.radio import (
    InvalidRadioUrlError,
    LinkState,
    Packet,
    Radio,
    RadioError,
    RadioUrl,
)
from particlebot.sim.harness import HarnessError
from particlebot.sim.swarm import EmulatedSwarm, SwarmConfig
from particlebot.virtual.light import Lamp

OPTIONS = {
    "loss",
    "delay_ms",
    "speed",
    "spacing",
    "start",
    "lamp",
    "seed",
    "elf",
    "base_baud",
    "buffer",
}
MAX_PARTICLES = 32
"""One harness process each; the firmware records at most 32 senders per round anyway."""


def swarm_config_from_url(url: RadioUrl) -> SwarmConfig:
    url.check_options(OPTIONS)
    try:
        count = int(url.target or "5")
    except ValueError:
        raise InvalidRadioUrlError(
            f"{url.text}: the number of particles goes after emulated://, e.g. emulated://5"
        ) from None
    if not 1 <= count <= MAX_PARTICLES:
        raise InvalidRadioUrlError(f"{url.text}: 1..{MAX_PARTICLES} particles, not {count}")
    loss = url.get_float("loss", 0.0)
    if not 0.0 <= loss < 1.0:
        raise InvalidRadioUrlError(f"{url.text}: loss is a probability below 1, e.g. loss=0.2")
    delay_ms = url.get_float("delay_ms", 0.0)
    if delay_ms < 0:
        raise InvalidRadioUrlError(f"{url.text}: delay_ms cannot be negative")
    lamp = Lamp()
    if "lamp" in url.options:
        try:
            parts = [float(p) for p in url.options["lamp"].split(",")]
        except ValueError:
            parts = []
        if len(parts) != 3 or parts[2] <= 0:
            raise InvalidRadioUrlError(
                f"{url.text}: lamp=X,Y,H in metres, H above the photocells, e.g. lamp=0,0,0.28"
            )
        lamp = Lamp(parts[0], parts[1], parts[2])
    elf = Path(url.options["elf"]) if "elf" in url.options else None
    base_baud = url.get_int("base_baud", 9600)
    buffer = url.get_int("buffer", 256)
    if base_baud <= 0 or buffer < 100:
        raise InvalidRadioUrlError(f"{url.text}: base_baud > 0 and buffer >= 100 bytes")
    return SwarmConfig(
        count=count,
        lamp=lamp,
        start=url.get_float("start", 0.10),
        spacing=url.get_float("spacing", 0.155),
        loss=loss,
        delay_us=delay_ms * 1000,
        seed=url.get_int("seed", 1),
        elf=elf,
        base_baud=base_baud,
        buffer_bytes=buffer,
        keep_history=False,
    )


def parse_speed(url: RadioUrl) -> float:
    text = url.options.get("speed", "1")
    speed = math.inf if text == "max" else url.get_float("speed", 1.0)
    if speed <= 0:
        raise InvalidRadioUrlError(f"{url.text}: speed must be positive, or max")
    return speed


class EmulatedRadio(Radio):
    """The base station's radio on an EmulatedSwarm's air. Its clock is the emulation's, so the
    console's ages and timeouts follow emulated time when it runs faster or slower than real."""

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
        super().__init__(url)
        self.swarm = swarm
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._owns_thread = speed is not None
        self._owns_swarm = owns_swarm
        swarm.add_base_listener(self._deliver)
        if speed is not None:
            swarm.start(speed)

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        config = swarm_config_from_url(url)
        speed = parse_speed(url)
        try:
            swarm = EmulatedSwarm(config)
        except (FileNotFoundError, HarnessError, OSError) as exc:
            raise RadioError(
                f"The emulated particles need the firmware image and the simavr harness ({exc}). "
                "Run: make firmware harness (after `make system-deps` for the AVR tools)"
            ) from exc
        return cls(swarm, url=url.text, speed=speed, owns_swarm=True)

    def _deliver(self, source: int, data: bytes, time_s: float) -> None:
        self._packets.put(
            Packet(data=data, source=self.swarm.node_name(source), time=self.swarm.epoch(time_s))
        )

    def now(self) -> float:
        return self.swarm.epoch()

    def send(self, data: bytes) -> None:
        self._check()
        self.swarm.send_from_base(data)

    def receive(self, timeout: float | None = None) -> Packet | None:
        self._check()
        try:
            return self._packets.get(timeout=timeout)
        except queue.Empty:
            self._check()
            return None

    def _check(self) -> None:
        error = self.swarm.error
        if error is not None:
            self._set_link(LinkState.LOST, f"the emulation stopped: {error}")
            raise RadioError(
                f"The emulated swarm stopped ({error}); rebuild with `make firmware harness` "
                "and open it again"
            )

    def close(self) -> None:
        if self._owns_thread:
            self.swarm.stop()
        if self._owns_swarm:
            self.swarm.close()
        super().close()
