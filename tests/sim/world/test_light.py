"""The light field: calibration, eq. 11 against eq. 14, and the six sensors' small differences."""

from __future__ import annotations

import itertools
import math

import pytest

from particlebot.sim.world.light import Lamp, LightField


def test_the_reference_point_under_the_lamp_reads_980_on_every_sensor() -> None:
    field = LightField(Lamp(0.0, 0.0, 0.28))
    assert field.sensor_values(0.0, 0.0) == [980] * 6


def test_readings_fall_with_distance_like_the_paper_line_of_particles() -> None:
    field = LightField()
    readings = [field.reading(0.1 + 0.155 * k, 0.0) for k in range(10)]
    assert all(a > b for a, b in itertools.pairwise(readings))
    # Neighbours 15.5 cm apart differ by more than method D's default tolerance of 10.
    assert min(a - b for a, b in itertools.pairwise(readings)) > 10


@pytest.mark.parametrize("ground", [0.0, 0.2, 0.75, 1.6])
def test_eq_14_recovers_the_distance_eq_11_was_computed_from(ground: float) -> None:
    field = LightField(Lamp(0.5, -0.3, 0.35))
    x, y = 0.5 + ground, -0.3
    reading = field.reading(x, y)
    # Independent arithmetic: r^2 = V_x (1023 - V) / (V (1023 - V_x)) r_x^2 with r_x = 0.28.
    r_squared = 980 * (1023 - reading) / (reading * (1023 - 980)) * 0.28**2
    assert math.sqrt(r_squared) == pytest.approx(math.hypot(ground, 0.35), rel=1e-9)
    assert field.distance_for_reading(reading) == pytest.approx(math.hypot(ground, 0.35))


def test_the_sensor_facing_the_lamp_reads_most_and_the_mean_stays_close() -> None:
    field = LightField()
    values = field.sensor_values(0.8, 0.0)  # lamp towards -x: sensor 3 faces it (180 deg)
    assert max(values) == values[3]
    assert min(values) == values[0]
    assert len(set(values)) > 1
    assert abs(sum(values) / 6 - field.reading(0.8, 0.0)) < 2


def test_noise_changes_readings_but_a_seed_repeats_them() -> None:
    noisy_a = LightField(noise=3.0, seed=5).sensor_values(0.5, 0.0)
    noisy_b = LightField(noise=3.0, seed=5).sensor_values(0.5, 0.0)
    clean = LightField().sensor_values(0.5, 0.0)
    assert noisy_a == noisy_b
    assert noisy_a != clean
