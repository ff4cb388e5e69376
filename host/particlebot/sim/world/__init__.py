"""The physical world every level of simulation shares: discs, arena, lamp, compiled stepping.

Names are imported lazily, so that the light model (world.light, which the virtual particles use)
does not pull numba in.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from particlebot.sim.world.arena import Arena, Circle, Rect
    from particlebot.sim.world.bodies import BodyState, DeadParticles, PassiveObject
    from particlebot.sim.world.light import Lamp, LightField, ShadowMode
    from particlebot.sim.world.params import PhysicsParams
    from particlebot.sim.world.world import Snapshot, World

_HOMES = {
    "Arena": "arena",
    "Circle": "arena",
    "Rect": "arena",
    "BodyState": "bodies",
    "DeadParticles": "bodies",
    "PassiveObject": "bodies",
    "Lamp": "light",
    "LightField": "light",
    "ShadowMode": "light",
    "PhysicsParams": "params",
    "Snapshot": "world",
    "World": "world",
}

__all__ = [
    "Arena",
    "BodyState",
    "Circle",
    "DeadParticles",
    "Lamp",
    "LightField",
    "PassiveObject",
    "PhysicsParams",
    "Rect",
    "ShadowMode",
    "Snapshot",
    "World",
]


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{home}"), name)
