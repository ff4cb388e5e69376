"""The air every simulated swarm shares: one 802.15.4 medium (medium.py), in the swarm's cycles."""

from particlebot.sim.air.medium import (
    BASE,
    BAUD,
    NOISE,
    AirPacket,
    Medium,
    Reception,
    SerialLine,
    char_cycles,
)

__all__ = [
    "BASE",
    "BAUD",
    "NOISE",
    "AirPacket",
    "Medium",
    "Reception",
    "SerialLine",
    "char_cycles",
]
