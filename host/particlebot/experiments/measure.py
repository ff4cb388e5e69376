"""What a simulated radio knows that a real one cannot: how far the swarm is from the lamp."""

from __future__ import annotations

import math

from particlebot.radio import Radio
from particlebot.radio._simulated import SwarmRadio
from particlebot.sim.swarm import EmulatedSwarm
from particlebot.virtual.swarm import VirtualSwarm


def lamp_distance(radio: Radio) -> float | None:
    """Ground distance (m) from the lamp's foot to the centroid of the particles, on a simulated
    radio whose particles move; None on a real one, and where they cannot move (emulated
    particles, virtual ones with kinematics=0): a distance that cannot change would read as a
    method that failed. The one place that reads the simulation's truth: when the 2-D world
    replaces today's line, only this function changes."""
    if not isinstance(radio, SwarmRadio):
        return None
    world = radio.swarm
    if isinstance(world, EmulatedSwarm):
        return None  # its particles stand where they were put
    if isinstance(world, VirtualSwarm) and world.config.kinematics:
        points = [(p.x, p.y) for p in world.snapshot()]
        lamp = world.config.lamp
    else:
        return None
    if not points:
        return None
    x = sum(point[0] for point in points) / len(points)
    y = sum(point[1] for point in points) / len(points)
    return math.hypot(x - lamp.x, y - lamp.y)
