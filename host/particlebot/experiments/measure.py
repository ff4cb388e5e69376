"""What a simulated radio knows and does that a real one cannot: how far the swarm is from the
lamp, and putting particles where a person would put them (calibration)."""

from __future__ import annotations

import math
from collections.abc import Mapping

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


def can_place(radio: Radio) -> bool:
    """Whether place() can move this radio's particles: a simulated swarm that its caller steps
    (moving particles under a stepping thread would race it)."""
    return isinstance(radio, SwarmRadio) and radio.stepped_by_caller


def place(radio: Radio, offsets: Mapping[int, tuple[float, float]]) -> None:
    """Puts each particle (by id) at (dx, dy) metres from the lamp's foot, as a person following
    a calibration's instructions would; its photocells see the light there from then on. The
    simulated line's particles have their A0 facing +x, away from a lamp at their -x. ValueError
    when the radio cannot (see can_place) or does not know an id. Like lamp_distance, the one
    place that changes the simulation's truth."""
    if not can_place(radio):
        raise ValueError(
            f"{radio.url}: only simulated particles stepped by the caller can be moved"
        )
    assert isinstance(radio, SwarmRadio)
    world = radio.swarm
    if isinstance(world, VirtualSwarm):
        index_of = {member.firmware.id: member.index for member in world.members}
        lamp = world.config.lamp
        move = world.move
    elif isinstance(world, EmulatedSwarm):
        index_of = {particle_id: index for index, particle_id in enumerate(world.ids)}
        lamp = world.config.lamp
        move = world.move
    else:
        raise ValueError(f"{radio.url}: cannot move these particles")
    unknown = sorted(set(offsets) - set(index_of))
    if unknown:
        raise ValueError(f"no simulated particle with id {', '.join(map(str, unknown))}")
    for particle_id, (dx, dy) in offsets.items():
        move(index_of[particle_id], lamp.x + dx, lamp.y + dy)
