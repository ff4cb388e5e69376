"""particlebot: firmware tooling, base-station console and virtual particles for particle robots.

Scripts drive a swarm through `particlebot.Swarm` (see README, "Experiments as code").
"""

__version__ = "0.1.0"
"""The package's version, in this one place: pyproject.toml reads it (setuptools' dynamic
version) and `particlebot --version` prints it."""

from particlebot.protocol import Method, Param, State
from particlebot.radio import RadioError
from particlebot.swarm.api import Swarm
from particlebot.swarm.results import (
    IdInUse,
    NotConfirmed,
    ParamReport,
    Particle,
    ParticlesMissing,
    Reply,
    Run,
    StopReport,
    SwarmError,
    Unconfirmed,
)

__all__ = [
    "IdInUse",
    "Method",
    "NotConfirmed",
    "Param",
    "ParamReport",
    "Particle",
    "ParticlesMissing",
    "RadioError",
    "Reply",
    "Run",
    "State",
    "StopReport",
    "Swarm",
    "SwarmError",
    "Unconfirmed",
]
