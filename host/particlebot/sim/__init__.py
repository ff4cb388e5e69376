"""Firmware in the loop: the real particle ELF running in simavr, driven from Python."""

from particlebot.sim.harness import (
    CPU_HZ,
    FAULT_PIN,
    HarnessError,
    ParticleSim,
    Reset,
    ServoPulse,
    UartByte,
    default_elf,
    default_harness,
)
from particlebot.sim.medium import BASE, NOISE, AirPacket, Medium, Reception
from particlebot.sim.swarm import (
    BaseStation,
    EmulatedSwarm,
    HeardFrame,
    SwarmConfig,
    eeprom_image,
    light_to_millivolts,
    node_name,
)

__all__ = [
    "BASE",
    "CPU_HZ",
    "FAULT_PIN",
    "NOISE",
    "AirPacket",
    "BaseStation",
    "EmulatedSwarm",
    "HarnessError",
    "HeardFrame",
    "Medium",
    "ParticleSim",
    "Reception",
    "Reset",
    "ServoPulse",
    "SwarmConfig",
    "UartByte",
    "default_elf",
    "default_harness",
    "eeprom_image",
    "light_to_millivolts",
    "node_name",
]
