"""What simulated particles are really doing, whatever the radio says: the tests' ground truth."""

from __future__ import annotations

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import State
from particlebot.virtual.swarm import VirtualSwarm


def true_states(world: VirtualSwarm) -> list[State]:
    """Each virtual particle's state, read from its logic rather than heard."""
    states = []
    for member in world.members:
        firmware = member.firmware
        assert isinstance(firmware, NativeParticle)
        states.append(State(firmware.status().state))
    return states
