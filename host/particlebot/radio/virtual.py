"""The base station on simulated air shared with virtual particles: virtual://N?lamp=X,Y,H."""

from __future__ import annotations

import random
from typing import Self

from particlebot.options import NON_NEGATIVE, POSITIVE, SWITCH
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
    Faults,
    LinkFaults,
    faults_from_url,
    scenario_from_url,
)
from particlebot.virtual import MAX_PARTICLES
from particlebot.virtual.swarm import SwarmConfig, VirtualSwarm

OPTIONS = {
    "lamp",
    "speed",
    "spacing",
    "start",
    "kinematics",
    "noise",
    "photocell_spread",
    *FAULT_OPTIONS,
    *SIMULATION_OPTIONS,
}
LOSS_SEED = 0x10557
"""Mixed into the seed for the losses, so they do not follow the particles' own random numbers."""


def swarm_config_from_url(url: RadioUrl) -> SwarmConfig:
    """virtual://N?lamp=X,Y,H&spacing=M&start=M&seed=S&kinematics=0|1&noise=SIGMA (metres)
    &photocell_spread=S."""
    url.check_options(OPTIONS)
    scenario_from_url(url)
    return SwarmConfig(
        count=parse_count(url, default=10, maximum=MAX_PARTICLES),
        lamp=parse_lamp(url),
        start=url.get_float("start", 0.10, NON_NEGATIVE),
        spacing=url.get_float("spacing", 0.155, POSITIVE),
        kinematics=url.get_int("kinematics", 1, SWITCH) != 0,
        seed=url.get_int("seed", 1, NON_NEGATIVE),
        noise=url.get_float("noise", 0.0, NON_NEGATIVE),
        photocell_spread=parse_photocell_spread(url),
    )


class VirtualRadio(SwarmRadio[VirtualSwarm]):
    """The base station's node on a VirtualSwarm's air."""

    def _connect(self) -> None:
        self.swarm.connect_base(lambda data, source, at: self._deliver(source, data, at))

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        config = swarm_config_from_url(url)
        speed = url.get_speed()  # checked either way
        pace = None if url.caller_steps else speed
        try:
            swarm = VirtualSwarm(config)
        except (OSError, ImportError) as exc:
            raise RadioError(
                f"The virtual particles need the firmware logic built for this PC ({exc}). "
                "Run: make native"
            ) from exc
        faults = faults_from_url(url)
        lose_on_air(swarm, faults.loss, config.seed)
        link = LinkFaults(Faults(delay_s=faults.delay_s)) if faults.delay_s else None
        return cls(swarm, url=url.text, speed=pace, link_faults=link)


def lose_on_air(swarm: VirtualSwarm, loss: float, seed: int) -> None:
    """Every copy of every packet, at every receiver on the virtual air, is lost with chance
    loss (as on the emulated medium), the same copies for the same seed."""
    if loss:
        rng = random.Random(seed ^ LOSS_SEED)
        swarm.air.drop = lambda source, receiver, data: rng.random() < loss
