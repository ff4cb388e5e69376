"""The servo table from measured radii, and the order its points are written in."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.calibration.photocells import CalibrationError
from particlebot.calibration.servo import (
    POINTS,
    check_measurements,
    monotonic,
    table_from_measurements,
    target_radii_mm,
    write_order,
)
from particlebot.protocol import PARAM_SPECS, Param

DEFAULT_TABLE = [PARAM_SPECS[Param(Param.SERVO_CAL_0 + k)].default for k in range(POINTS)]
R_MIN, R_MAX = PARAM_SPECS[Param.RADIUS_MIN_UM].default, PARAM_SPECS[Param.RADIUS_MAX_UM].default


def transmission(pulse: float) -> float:
    """A made-up servo and linkage: radius (mm) for a pulse, far from linear."""
    return 70 + 55 * math.sin(math.pi / 2 * (pulse - 950) / 900)


def test_the_targets_are_nine_radii_from_r_min_to_r_max() -> None:
    targets = target_radii_mm(R_MIN, R_MAX)
    assert targets[0] == R_MIN / 1000 and targets[-1] == R_MAX / 1000
    assert np.allclose(np.diff(targets), (R_MAX - R_MIN) / 8000)


def test_the_new_table_puts_the_measured_servo_at_its_target_radii() -> None:
    pulses = [900 + 110 * k for k in range(POINTS)]
    radii = [transmission(p) for p in pulses]
    targets = target_radii_mm(R_MIN, R_MAX)
    table = table_from_measurements(pulses, radii, targets)
    assert not table.extrapolated
    achieved = [transmission(p) for p in table.pulses]
    # Linear between points 110 us apart on a sine: within half a millimetre.
    assert np.max(np.abs(np.array(achieved) - targets)) < 0.5
    assert monotonic(table.pulses)


def test_targets_beyond_the_measured_radii_are_extended_and_said_so() -> None:
    pulses = DEFAULT_TABLE
    radii = [80 + 3 * k for k in range(POINTS)]  # 80..104 mm: short of 77.5 and 117.5
    table = table_from_measurements(pulses, radii, target_radii_mm(R_MIN, R_MAX))
    assert table.extrapolated == (0, 6, 7, 8)
    assert table.pulses[0] < DEFAULT_TABLE[0] and table.pulses[-1] > DEFAULT_TABLE[-1]


def test_a_servo_mounted_the_other_way_gives_a_falling_table() -> None:
    pulses = DEFAULT_TABLE
    radii = [130 - 6 * k for k in range(POINTS)]
    table = table_from_measurements(pulses, radii, target_radii_mm(R_MIN, R_MAX))
    assert list(table.pulses) == sorted(table.pulses, reverse=True)


def test_radii_that_do_not_follow_the_pulse_name_the_point() -> None:
    radii = [77.5, 82, 87, 92, 91, 100, 105, 110, 115]
    with pytest.raises(
        CalibrationError, match=r"point 4 \(91 mm at 1370 us\) is not above point 3"
    ):
        check_measurements(DEFAULT_TABLE, radii)
    with pytest.raises(CalibrationError, match="same pulse"):
        check_measurements([1000] * 2 + DEFAULT_TABLE[2:], [77.5 + k for k in range(POINTS)])


def monotonic_tables() -> st.SearchStrategy[list[int]]:
    pulses = st.lists(st.integers(500, 2500), min_size=POINTS, max_size=POINTS)
    return st.tuples(pulses, st.booleans()).map(lambda pair: sorted(pair[0], reverse=pair[1]))


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(old=monotonic_tables(), new=monotonic_tables())
def test_every_intermediate_table_of_the_write_order_is_monotonic(
    old: list[int], new: list[int]
) -> None:
    table = list(old)
    for point, pulse in write_order(old, new):
        table[point] = pulse
        assert monotonic(table), (old, new, table)
    assert table == new


def test_a_table_that_is_not_monotonic_is_never_written() -> None:
    with pytest.raises(CalibrationError, match="not monotonic"):
        write_order(DEFAULT_TABLE, [1000, 1200, 1100, *DEFAULT_TABLE[3:]])
