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

__all__ = [
    "CPU_HZ",
    "FAULT_PIN",
    "HarnessError",
    "ParticleSim",
    "Reset",
    "ServoPulse",
    "UartByte",
    "default_elf",
    "default_harness",
]
