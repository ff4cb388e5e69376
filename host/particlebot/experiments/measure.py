"""What a simulated radio knows and does that a real one cannot: how far the swarm is from the
lamp, and putting particles where a person would put them (calibration)."""

from __future__ import annotations

import math
from collections.abc import Mapping

from particlebot.radio import Radio
from particlebot.radio.simulated import SwarmRadio


def lamp_distance(radio: Radio) -> float | None:
    """Ground distance (m) from the lamp's foot to the centroid of the particles' bodies, on a
    simulated radio whose world moves them; None on a real one, and where they cannot move
    (kinematics=0): a distance that cannot change would read as a method that failed. The one
    place that reads the simulation's truth."""
    if not isinstance(radio, SwarmRadio) or not radio.swarm.config.kinematics:
        return None
    points = radio.swarm.snapshot()
    if not points:
        return None
    x = sum(point.x for point in points) / len(points)
    y = sum(point.y for point in points) / len(points)
    lamp = radio.swarm.world.lamp
    return math.hypot(x - lamp.x, y - lamp.y)


def can_place(radio: Radio) -> bool:
    """Whether place() can move this radio's particles: a simulated swarm that its caller steps
    (moving particles under a stepping thread would race it)."""
    return isinstance(radio, SwarmRadio) and radio.stepped_by_caller


def place(radio: Radio, offsets: Mapping[int, tuple[float, float]]) -> None:
    """Puts each particle (by id) at (dx, dy) metres from the lamp's foot, as a person following
    a calibration's instructions would; its photocells see the light there from then on. The
    simulated particles' A0 faces +x, away from a lamp at their -x. ValueError when the radio
    cannot (see can_place) or does not know an id. Like lamp_distance, the one place that changes
    the simulation's truth."""
    if not can_place(radio):
        raise ValueError(
            f"{radio.url}: only simulated particles stepped by the caller can be moved"
        )
    assert isinstance(radio, SwarmRadio)
    swarm = radio.swarm
    index_of = {particle_id: index for index, particle_id in enumerate(swarm.ids)}
    unknown = sorted(set(offsets) - set(index_of))
    if unknown:
        raise ValueError(f"no simulated particle with id {', '.join(map(str, unknown))}")
    lamp = swarm.world.lamp
    for particle_id, (dx, dy) in offsets.items():
        swarm.place(index_of[particle_id], lamp.x + dx, lamp.y + dy)
