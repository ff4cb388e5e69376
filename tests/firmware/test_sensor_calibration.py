"""Photocell calibration (SENSOR_GAMMA_k, SENSOR_GAIN_k): the firmware's fixed-point correction
against the formula, and eq. 14 holding for non-ideal photocells once they are calibrated."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.firmware.native import calibrated_reading
from particlebot.protocol import PARAM_SPECS, Param, ParamResult
from tests.firmware.conftest import REF_DISTANCE_M, REF_VALUE, Bench

GAMMAS = [Param(Param.SENSOR_GAMMA_0 + k) for k in range(6)]
GAINS = [Param(Param.SENSOR_GAIN_0 + k) for k in range(6)]
# rho = R / R_R at the reference point (eq. 13 over the load): what an ideal cell reads there.
REF_RHO = (1023 - REF_VALUE) / REF_VALUE


def formula(raw: int, gamma_milli: int, gain_milli: int) -> float:
    """rho' = gain * rho^(1 / gamma), reading 1023 / (1 + rho'), within 1..1022."""
    rho = (1023 - raw) / raw
    reading = 1023 / (1 + gain_milli / 1000 * rho ** (1000 / gamma_milli))
    return min(max(reading, 1.0), 1022.0)


def test_the_defaults_leave_every_reading_as_it_is() -> None:
    gamma, gain = (
        PARAM_SPECS[Param.SENSOR_GAMMA_0].default,
        PARAM_SPECS[Param.SENSOR_GAIN_0].default,
    )
    assert [calibrated_reading(raw, gamma, gain) for raw in range(1024)] == list(range(1024))


@settings(max_examples=2000, deadline=None)
@given(
    raw=st.integers(1, 1022),
    gamma=st.integers(PARAM_SPECS[Param.SENSOR_GAMMA_0].min, PARAM_SPECS[Param.SENSOR_GAMMA_0].max),
    gain=st.integers(PARAM_SPECS[Param.SENSOR_GAIN_0].min, PARAM_SPECS[Param.SENSOR_GAIN_0].max),
)
def test_the_fixed_point_correction_is_within_one_count_of_the_formula(
    raw: int, gamma: int, gain: int
) -> None:
    assert abs(calibrated_reading(raw, gamma, gain) - formula(raw, gamma, gain)) <= 1.0


class Photocell:
    """A CdS cell whose resistance follows rho = c * rho_x * (r / r_x)^(2 gamma): gamma of eq. 7
    and a scale c, both 1 for the ideal cell eq. 11 describes."""

    def __init__(self, gamma: float, scale: float) -> None:
        self.gamma = gamma
        self.scale = scale

    def reading(self, distance_m: float) -> int:
        rho = self.scale * REF_RHO * (distance_m / REF_DISTANCE_M) ** (2 * self.gamma)
        return round(1023 / (1 + rho))

    def calibration(self) -> tuple[int, int]:
        """SENSOR_GAMMA_k and SENSOR_GAIN_k that map this cell onto the ideal one:
        gain * rho^(1 / gamma) = rho_x * (r / r_x)^2."""
        gain = REF_RHO / (self.scale * REF_RHO) ** (1 / self.gamma)
        return round(self.gamma * 1000), round(gain * 1000)


def eq14_distance_m(reading: int) -> float:
    """Eq. 14: r_n from V_n with the reference V_x = 980 at r_x = 28 cm."""
    ratio = REF_VALUE * (1023 - reading) / (reading * (1023 - REF_VALUE))
    return REF_DISTANCE_M * math.sqrt(ratio)


# Six cells of one particle, as unlike as CdS cells of one type come (gamma 0.7-1.3, resistance
# at the same light 0.6-1.6 times the nominal).
CELLS = [
    Photocell(0.72, 1.45),
    Photocell(0.85, 0.62),
    Photocell(1.00, 1.30),
    Photocell(1.12, 0.80),
    Photocell(1.27, 1.10),
    Photocell(0.93, 1.58),
]
DISTANCES_M = [0.30, 0.40, 0.55, 0.75, 1.00]


def estimated_distances(bench: Bench) -> list[float]:
    """Eq. 14 applied to the particle's STATUS intensity at each of DISTANCES_M."""
    estimates = []
    for distance in DISTANCES_M:
        bench.particle.set_adc([cell.reading(distance) for cell in CELLS])
        bench.advance(100)  # two whole readings
        estimates.append(eq14_distance_m(bench.status().intensity))
    return estimates


def test_calibrated_photocells_make_eq14_hold(bench: Bench) -> None:
    before = estimated_distances(bench)
    worst_before = max(abs(e / d - 1) for e, d in zip(before, DISTANCES_M, strict=True))
    assert worst_before > 0.05  # uncalibrated, eq. 14 misjudges the distance by 6 %
    for k, cell in enumerate(CELLS):
        gamma, gain = cell.calibration()
        assert bench.set_param(GAMMAS[k], gamma).result == ParamResult.OK
        assert bench.set_param(GAINS[k], gain).result == ParamResult.OK
    after = estimated_distances(bench)
    for estimate, distance in zip(after, DISTANCES_M, strict=True):
        assert estimate == pytest.approx(distance, rel=0.005)
    # The raw readings are still reported, for the next calibration.
    assert list(bench.status().sensors) == [cell.reading(DISTANCES_M[-1]) for cell in CELLS]
