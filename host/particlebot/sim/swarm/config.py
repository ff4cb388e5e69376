"""What a simulated swarm of firmware particles is made of: the scenario (where everything is), the
level its particles run at, their hardware, and the air between them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum
from pathlib import Path

from particlebot.protocol import Param
from particlebot.sim.air.medium import BAUD, DEFAULT_BUFFER_BYTES
from particlebot.sim.scenarios import presets
from particlebot.sim.scenarios.scenario import Scenario

TRUTH_BODIES_S = 0.5
"""The world's truth (every particle's position and radius) is recorded this often: 2 Hz, far
faster than a swarm moves and a modest size in a session log."""
TRUTH_RADII_S = 0.1
"""Each particle's commanded radius is recorded this often: 15 samples of the shortest cycle
(T = 1.5 s), so a plot draws its shape rather than aliases of it."""


class Level(StrEnum):
    """What runs in each particle."""

    NATIVE = "native"
    """The firmware logic, firmware/lib, built for the PC (virtual://)."""
    EMULATED = "emulated"
    """The flashed image, particle.elf, in simavr (emulated://)."""


def default_scenario() -> Scenario:
    return presets.line(5)


@dataclass(frozen=True)
class SwarmConfig:
    """A swarm of particles running our firmware in the world of a scenario.

    The scenario says where the particles, the lamp and the obstacles are and how the world
    behaves (its physics, its shadows, the placement's seed); its controller section is not used:
    the firmware in the particles decides, as the base station starts it.
    """

    scenario: Scenario = field(default_factory=default_scenario)
    level: Level = Level.NATIVE
    count: int | None = None
    """Robot particles; None: the scenario's."""
    first_id: int = 1
    params: Mapping[Param, int] = field(default_factory=dict)
    """Parameter values preset in every particle's EEPROM (the rest their defaults)."""
    seed: int = 1
    """Seeds the air's losses and, with each particle's index, the particles' own random numbers
    (the scenario's seed places them)."""

    # ---- the air ----
    loss: float = 0.0
    """Probability that one receiver misses one copy of a packet."""
    delay_us: float = 0.0
    """Added to every packet's airtime before receivers have it."""
    buffer_bytes: int = DEFAULT_BUFFER_BYTES
    """A radio's buffer towards its host: a packet that does not fit is dropped."""
    base_baud: int = BAUD
    """The base station radio's serial rate (particles' radios run at 9600)."""

    # ---- the particles' hardware ----
    photocell_spread: float = 0.0
    """0: every photocell the ideal one; s: gamma within 1 +- s and so on (Photocells.spread)."""
    noise: float = 0.0
    """Standard deviation (counts) of the noise on each photocell reading."""
    kinematics: bool = True
    """False: the bodies stay where they were put (the world is not stepped)."""

    # ---- emulated particles only ----
    quantum_us: float = 2000.0
    """Longest lockstep step of the emulated particles (at most 3 ms: see MAX_QUANTUM_US)."""
    elf: Path | None = None
    """The firmware image (default: build/firmware/particle.elf)."""
    fault_elf: Sequence[int] = ()
    """Indices of particles that run build/firmware/particle-faults.elf instead."""
    harness: Path | None = None
    keep_history: bool = True
    """Keep every UART byte, servo pulse and packet (tests); off, memory stays bounded."""

    def resolved_scenario(self) -> Scenario:
        """The scenario as run: with `count` particles when given."""
        if self.count is None:
            return self.scenario
        return presets.with_particles(self.scenario, self.count)

    def with_scenario(self, scenario: Scenario) -> SwarmConfig:
        return replace(self, scenario=scenario)
