"""The one interface of particles that run our firmware (native logic or emulated image): sensor
readings and bytes in, the servo's radius and bytes out, on the swarm's clock."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from particlebot.sim.air.medium import Reception

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SerialByte:
    """A byte a particle's firmware wrote to its radio: which particle, the cycle at which the
    byte has fully reached the radio, its value."""

    index: int
    cycle: int
    value: int


class FirmwareParticles(ABC):
    """K particles running the firmware, indices 0..K-1, ids as given, stepped together.

    The swarm (particlebot.sim.swarm) drives them: run_until() moves them to a cycle and returns
    what they wrote to their radios meanwhile; receive() hands one of them a packet its radio
    got; set_light() changes what its photocells read; radii_m() is where each servo drives its
    body. All times are cycles of particlebot.sim.clock.
    """

    level: str
    """'native' or 'emulated', as the URL scheme and the logs name it."""
    exact_air: bool
    """True when a step must end wherever the air acts (the emulated UART takes each byte at its
    own cycle); False when the particles only act at their own ticks and take bytes there."""

    def __init__(self, ids: Sequence[int]) -> None:
        self.ids = list(ids)

    @property
    def count(self) -> int:
        return len(self.ids)

    @abstractmethod
    def node_name(self, index: int) -> str:
        """The name its radio goes by on the base station (what logs and the console show)."""

    @abstractmethod
    def next_stop(self, cycle: int) -> int:
        """The furthest cycle after `cycle` a step may run to (the next tick; a quantum)."""

    @abstractmethod
    def run_until(self, cycle: int) -> list[SerialByte]:
        """Runs every particle to `cycle`; returns the bytes they wrote to their radios, each
        particle's in time order (a native particle's may be stamped after `cycle`: a frame it
        hands over goes out byte by byte at 9600 baud)."""

    @abstractmethod
    def receive(self, copy: Reception) -> None:
        """A packet its radio got (copy.receiver is the particle's index), its bytes reaching the
        firmware at copy.byte_end(i)."""

    @abstractmethod
    def set_light(self, index: int, readings: Sequence[int]) -> None:
        """Photocells A0..A5 of particle index read these (0..1023) from now on."""

    @abstractmethod
    def radii_m(self) -> FloatArray:
        """The radius (m) each particle's servo drives its body to now."""

    @abstractmethod
    def close(self) -> None:
        """Ends what the particles hold (processes, library handles)."""
