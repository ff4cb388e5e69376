"""Native particles: the firmware logic (firmware/lib) built for the PC, driven through ctypes."""

from particlebot.sim.particles.native.particles import (
    FirmwareParticle,
    NativeParticles,
    ParticleFactory,
    native_factory,
)

__all__ = ["FirmwareParticle", "NativeParticles", "ParticleFactory", "native_factory"]
