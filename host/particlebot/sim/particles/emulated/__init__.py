"""Emulated particles: the flashed image (particle.elf) in simavr, one harness process each."""

from particlebot.sim.particles.emulated.harness import (
    FAULT_PIN,
    HarnessError,
    ParticleSim,
    Reset,
    ServoPulse,
    UartByte,
    default_elf,
    default_harness,
)
from particlebot.sim.particles.emulated.particles import (
    EmulatedParticles,
    light_to_millivolts,
    node_name,
)

__all__ = [
    "FAULT_PIN",
    "EmulatedParticles",
    "HarnessError",
    "ParticleSim",
    "Reset",
    "ServoPulse",
    "UartByte",
    "default_elf",
    "default_harness",
    "light_to_millivolts",
    "node_name",
]
