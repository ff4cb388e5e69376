"""particlebot: firmware tooling, base-station console and virtual particles for particle robots.

Scripts drive a swarm through `particlebot.Swarm` (see README, "Experiments as code").
"""

from particlebot.errors import ParticlebotError
from particlebot.protocol import Method, Param, State
from particlebot.radio import RadioError
from particlebot.swarm.api import Swarm
from particlebot.swarm.campaigns import Verdict
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
    "ParticlebotError",
    "ParticlesMissing",
    "RadioError",
    "Reply",
    "Run",
    "State",
    "StopReport",
    "Swarm",
    "SwarmError",
    "Unconfirmed",
    "Verdict",
]
