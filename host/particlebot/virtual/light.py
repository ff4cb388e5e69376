"""The virtual particles' light: the world's lamp model (sim.world.light), re-exported."""

from particlebot.sim.world.light import (
    ADC_FULL_SCALE,
    LOAD_OHM,
    REFERENCE_DISTANCE_M,
    REFERENCE_VALUE,
    SENSOR_COUNT,
    Lamp,
    LightField,
)

__all__ = [
    "ADC_FULL_SCALE",
    "LOAD_OHM",
    "REFERENCE_DISTANCE_M",
    "REFERENCE_VALUE",
    "SENSOR_COUNT",
    "Lamp",
    "LightField",
]
