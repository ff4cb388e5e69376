"""One clock stepping the world, the particles and the air (swarm.py), what a swarm is made of
(config.py), the base station's end for tests (base.py), pacing to the wall clock (pacing.py)."""

from particlebot.sim.swarm.config import Level, SwarmConfig
from particlebot.sim.swarm.swarm import ParticleSnapshot, SimSwarm

__all__ = ["Level", "ParticleSnapshot", "SimSwarm", "SwarmConfig"]
