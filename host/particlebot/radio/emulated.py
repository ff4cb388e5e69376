"""The base station on the air of emulated particles, the flashed image in simavr, in the world of
a scenario: emulated://K?scenario=line|blob|PATH&loss=0.2&delay_ms=5&speed=1&elf=PATH
&base_baud=9600&buffer=256 and every option virtual:// takes. K particles (ids 1..K), each the
ELF that `make firmware` builds (or a wheel carries), in the simavr harness. speed=max runs as fast
as the machine allows."""

from __future__ import annotations

from pathlib import Path
from typing import Self

from particlebot import resources
from particlebot.options import POSITIVE, Bounds
from particlebot.radio.base import RadioUrl
from particlebot.radio.simulated import SwarmRadio, swarm_config_from_url
from particlebot.radio.sizes import EMULATED_MAX_PARTICLES
from particlebot.sim.particles.emulated.harness import HarnessBuildError
from particlebot.sim.swarm.config import Level, SwarmConfig

OPTIONS = frozenset({"elf", "base_baud", "buffer"})
"""What emulated:// takes on top of virtual://'s options."""
MAX_PARTICLES = EMULATED_MAX_PARTICLES
DEFAULT_PARTICLES = 5


def emulated_config(url: RadioUrl) -> SwarmConfig:
    return swarm_config_from_url(
        url,
        Level.EMULATED,
        default_count=DEFAULT_PARTICLES,
        maximum=MAX_PARTICLES,
        extra=OPTIONS,
        elf=Path(url.options["elf"]) if "elf" in url.options else None,
        base_baud=url.get_int("base_baud", 9600, POSITIVE),
        # A whole 100-byte RF packet must fit, or the radio could never pass one on.
        buffer_bytes=url.get_int("buffer", 256, Bounds(minimum=100)),
    )


class EmulatedRadio(SwarmRadio):
    """The base station's radio on the air of a swarm of emulated particles."""

    restart_advice = "rebuild with `make firmware harness` and open it again"

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        return cls.open_swarm(emulated_config(url), url)

    @staticmethod
    def missing_advice(exc: BaseException) -> str:
        if isinstance(exc, HarnessBuildError):  # names the packages to install
            return str(exc)
        if resources.source_root() is None:
            return f"The emulated particles cannot start: {exc}"
        return (
            f"The emulated particles need the firmware image and the simavr harness ({exc}). "
            "Run: make firmware harness (after `make system-deps` for the AVR tools)"
        )
