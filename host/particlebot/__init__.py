"""particlebot: firmware tooling, base-station console and virtual particles for particle robots.

Scripts drive a swarm through `particlebot.Swarm` (see README, "Experiments as code").
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

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

__version__ = "0.1.0"
"""The package's version, in this one place: pyproject.toml reads it (setuptools' dynamic
version) and `particlebot --version` prints it."""

if TYPE_CHECKING:
    from particlebot.sim.runs.tables import RunTables


def read_run(folder: str | Path) -> RunTables:
    """A simulated run's folder as pandas DataFrames: .track (the centroid at every dump
    interval) and .frames (every body at every frame of trajectory.gsd, else of the
    snapshots). Imported when called, so that `import particlebot` stays light."""
    from particlebot.sim.runs.tables import read_run as read

    return read(folder)


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
    "read_run",
]
