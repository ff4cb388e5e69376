"""Vectorised controllers: every particle's commanded radius computed at once, for up to 10^6."""

from particlebot.sim.particles.model.controller import Controller, WorldView

__all__ = ["Controller", "WorldView"]
