"""How an emulated swarm is set up: the light each particle's photocells see, as voltages."""

from __future__ import annotations

from particlebot.sim.particles.emulated.particles import light_to_millivolts


def test_light_readings_become_the_divider_voltage_at_3v3() -> None:
    assert light_to_millivolts(0) == 0
    assert light_to_millivolts(1023) == 3300
    assert light_to_millivolts(980) == round(980 * 3300 / 1023)
    assert light_to_millivolts(2000) == 3300
