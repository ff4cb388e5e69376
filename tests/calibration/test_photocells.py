"""Photocells: the simulated spread, the fit of gamma and gain, and eq. 14 holding afterwards."""

from __future__ import annotations

import math

import numpy as np
import pytest

from particlebot.calibration.photocells import (
    CalibrationError,
    Correction,
    calibrate,
    corrected_reading,
    fit_cell,
    light_level,
    reference_value,
)
from particlebot.calibration.readings import Reading, Readings
from particlebot.firmware.native import calibrated_reading
from particlebot.fleet import PhotocellLaw
from particlebot.sim.world.light import Lamp, LightField
from particlebot.sim.world.photocells import Photocells

LAMP_HEIGHT_CM = 28.0
DISTANCES_CM = [20.0, 40.0, 70.0, 100.0]


def readings_of(field: LightField, count: int, distances_cm: list[float]) -> Readings:
    """What each particle's photocells read at each floor distance (no particle moved off)."""
    rows = [
        Reading(
            step=step,
            id=p + 1,
            distance_cm=d,
            lux=None,
            sensors=tuple(float(v) for v in field.sensor_values(d / 100, 0.0, particle=p)),
        )
        for step, d in enumerate(distances_cm, start=1)
        for p in range(count)
    ]
    return Readings(rows, {"lamp_height_cm": f"{LAMP_HEIGHT_CM:g}"})


def spread_field(spread: float, count: int, seed: int = 3) -> LightField:
    # No direction gain: each cell then follows its power law exactly, what the fit assumes.
    return LightField(
        Lamp(0, 0, LAMP_HEIGHT_CM / 100),
        direction_gain=0.0,
        photocells=Photocells.spread(count, spread, seed),
    )


def test_without_a_spread_every_reading_is_what_it_was() -> None:
    ideal = LightField()
    alike = LightField(photocells=Photocells.spread(3, 0.0, seed=9))
    xs, ys = np.array([0.0, 0.3, 1.2]), np.array([0.0, 0.1, -0.4])
    assert np.array_equal(ideal.sensor_matrix(xs, ys), alike.sensor_matrix(xs, ys))


def test_a_spread_is_seeded_and_each_particle_keeps_its_cells_whatever_the_count() -> None:
    a, b = Photocells.spread(4, 0.1, seed=2), Photocells.spread(9, 0.1, seed=2)
    assert np.array_equal(a.gamma, b.gamma[:4]) and np.array_equal(a.factor, b.factor[:4])
    assert not np.array_equal(a.gamma, Photocells.spread(4, 0.1, seed=3).gamma)
    assert b.gamma.min() >= 0.9 and b.gamma.max() <= 1.1
    assert np.exp(-0.3) <= b.factor.min() and b.factor.max() <= np.exp(0.3)
    with pytest.raises(ValueError, match=r"0\.\.0\.5"):
        Photocells.spread(2, 0.7, seed=1)


def test_a_cell_reads_its_own_law_rho_equals_factor_times_darkness_to_gamma() -> None:
    cells = Photocells(np.array([[0.9, 1.0, 1.1, 1.0, 1.0, 1.0]]), np.array([[1.2] + [1.0] * 5]))
    field = LightField(direction_gain=0.0, photocells=cells)
    rho_x = 43 / 980  # the SI's reference: 980 at 28 cm
    for ground in (0.0, 0.5):
        darkness = (ground**2 + 0.28**2) / 0.28**2
        values = field.sensor_values(ground, 0.0)
        for k in range(3):
            expected = 1023 / (1 + cells.factor[0, k] * rho_x * darkness ** cells.gamma[0, k])
            assert values[k] == round(expected)


def test_the_fit_recovers_each_cells_gamma_from_readings_at_four_distances() -> None:
    count = 5
    field = spread_field(0.15, count)
    result = calibrate(readings_of(field, count, DISTANCES_CM), LAMP_HEIGHT_CM)
    assert field.photocells is not None
    fitted = np.array(
        [[cell.gamma if cell else np.nan for cell in fit.cells] for fit in result.fits]
    )
    # Readings are whole counts: near the lamp one count is 2.4 % of rho.
    assert np.abs(fitted - field.photocells.gamma).max() < 0.02
    assert not result.kept_law


def test_exact_readings_give_exact_gamma_and_scale() -> None:
    gamma, c = 1.07, 0.61
    levels = np.array([0.1, 0.3, 0.9])
    values = 1023 / (1 + c * levels**gamma)
    fit = fit_cell(levels, values)
    assert fit.gamma == pytest.approx(gamma, abs=1e-9)
    assert math.exp(fit.log_c) == pytest.approx(c, rel=1e-9)


def test_after_the_firmwares_correction_every_cell_follows_the_fleets_law() -> None:
    count = 4
    field = spread_field(0.15, count, seed=11)
    readings = readings_of(field, count, DISTANCES_CM)
    result = calibrate(readings, LAMP_HEIGHT_CM)
    scale = result.law.scale
    worst_before = worst_after = 0.0
    for row in readings.rows:
        correction = result.corrections[row.id]
        x = light_level(row, LAMP_HEIGHT_CM)
        for k, raw in enumerate(row.sensors):
            fixed = calibrated_reading(
                int(raw), correction.gamma_milli[k], correction.gain_milli[k]
            )  # the firmware's own arithmetic
            assert abs(fixed - corrected_reading(raw, *_params(correction, k))) <= 1
            worst_before = max(worst_before, abs((1023 - raw) / raw / (scale * x) - 1))
            worst_after = max(worst_after, abs((1023 - fixed) / fixed / (scale * x) - 1))
    assert worst_before > 0.3
    assert worst_after < 0.04  # within a count or two of the law, near the lamp included


def _params(correction: Correction, k: int) -> tuple[int, int]:
    return correction.gamma_milli[k], correction.gain_milli[k]


def test_calibrated_cells_read_v_x_at_the_reference_point_as_the_law_says() -> None:
    count = 3
    field = spread_field(0.1, count, seed=5)
    result = calibrate(readings_of(field, count, DISTANCES_CM), LAMP_HEIGHT_CM)
    expected = reference_value(result.law.scale, (LAMP_HEIGHT_CM / 100) ** 2)
    for p in range(count):
        correction = result.corrections[p + 1]
        raw = field.sensor_values(0.0, 0.0, particle=p)
        fixed = [calibrated_reading(v, *_params(correction, k)) for k, v in enumerate(raw)]
        assert abs(np.mean(fixed) - expected) <= 1.5


def test_a_kept_law_puts_new_particles_on_the_fleets_scale() -> None:
    field = spread_field(0.1, 2)
    law = PhotocellLaw(0.5, "m2")
    result = calibrate(readings_of(field, 2, DISTANCES_CM), LAMP_HEIGHT_CM, law)
    assert result.kept_law and result.law.scale == 0.5
    with pytest.raises(CalibrationError, match="in 1/lux, these readings are in m2"):
        calibrate(readings_of(field, 2, DISTANCES_CM), LAMP_HEIGHT_CM, PhotocellLaw(1.0, "1/lux"))


def test_readings_at_one_distance_cannot_be_fitted() -> None:
    readings = readings_of(spread_field(0.1, 2), 2, [40.0])
    with pytest.raises(CalibrationError, match=r"particle 1 has readings at one distance only"):
        calibrate(readings, LAMP_HEIGHT_CM)


def test_particles_that_were_not_moved_are_named() -> None:
    field = spread_field(0.1, 1)
    readings = readings_of(field, 1, [40.0])
    moved_not = Readings(
        [readings.rows[0], Reading(2, 1, 80.0, None, readings.rows[0].sensors)], readings.meta
    )
    with pytest.raises(CalibrationError, match="hardly changed from 40 cm to 80 cm"):
        calibrate(moved_not, LAMP_HEIGHT_CM)


def test_lux_readings_fit_on_inverse_illuminance() -> None:
    gamma, c = 0.93, 12.0
    rows = [
        Reading(i, 4, None, lux, tuple([1023 / (1 + c * (1 / lux) ** gamma)] * 6))
        for i, lux in enumerate([10.0, 40.0, 200.0, 800.0])
    ]
    result = calibrate(Readings(rows), LAMP_HEIGHT_CM)
    assert result.law.unit == "1/lux"
    assert result.fits[0].cells[0] is not None
    assert result.fits[0].cells[0].gamma == pytest.approx(gamma, abs=0.01)


def test_a_stuck_cell_is_left_as_it_is_and_said_so() -> None:
    field = spread_field(0.1, 1)
    readings = readings_of(field, 1, DISTANCES_CM)
    stuck = [
        Reading(r.step, r.id, r.distance_cm, None, (1023.0, *r.sensors[1:]), faults=1)
        for r in readings.rows
    ]
    result = calibrate(Readings(stuck), LAMP_HEIGHT_CM)
    assert result.fits[0].cells[0] is None
    assert result.corrections[1].gamma_milli[0] == 1000
    assert "A0: stuck" in result.fits[0].skipped[0]
