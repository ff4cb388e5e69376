"""The base station on the air of virtual particles, the firmware logic built for the PC, in the
world of a scenario: virtual://N?scenario=line|blob|PATH&lamp=X,Y,H&speed=K|max&loss=P..."""

from __future__ import annotations

from typing import Self

from particlebot.radio.base import RadioUrl
from particlebot.radio.simulated import SwarmRadio, swarm_config_from_url
from particlebot.radio.sizes import VIRTUAL_MAX_PARTICLES as MAX_PARTICLES
from particlebot.sim.swarm.config import Level, SwarmConfig

DEFAULT_PARTICLES = 10


def virtual_config(url: RadioUrl) -> SwarmConfig:
    """virtual://N?scenario=line|blob|PATH&lamp=X,Y,H&spacing=M&start=M&seed=S&kinematics=0|1
    &noise=SIGMA&photocell_spread=S&loss=P&delay_ms=MS (metres)."""
    return swarm_config_from_url(
        url, Level.NATIVE, default_count=DEFAULT_PARTICLES, maximum=MAX_PARTICLES
    )


class VirtualRadio(SwarmRadio):
    """The base station's node on the air of a swarm of native particles."""

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        return cls.open_swarm(virtual_config(url), url)

    @staticmethod
    def missing_advice(exc: BaseException) -> str:
        return (
            f"The virtual particles need the firmware logic built for this PC ({exc}). "
            "Run: make native"
        )
