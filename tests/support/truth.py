"""What simulated particles are really doing, whatever the radio says: the tests' ground truth."""

from __future__ import annotations

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import State
from particlebot.sim.swarm import SimSwarm


def true_states(world: SimSwarm) -> list[State]:
    """Each virtual particle's state, read from its logic rather than heard."""
    states = []
    for firmware in world.native.firmware:
        assert isinstance(firmware, NativeParticle)
        states.append(State(firmware.status().state))
    return states
