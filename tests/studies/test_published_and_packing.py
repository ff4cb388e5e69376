"""The paper's transcribed tables agree with each other, and our packing diameters with Table S6."""

from __future__ import annotations

import math

import pytest

from particlebot.studies import published as paper
from particlebot.studies.dpd_table import DPD_DIAMETERS
from particlebot.studies.packing import (
    compute_densest_packing,
    densest_packing_diameter_m,
    densest_packing_diameters,
    hexagonal_lattice_diameters,
)

# A value printed with two decimals is within half a unit of the last digit.
HALF_DIGIT = 0.005


def test_table_s4_is_table_s3_in_percent_of_a_diameter_per_cycle() -> None:
    factor = paper.speed_to_percent_diameter_per_cycle(1.0)
    checked = 0
    for n, row in paper.TABLE_S3_MM_S.items():
        for fraction, s3 in row.items():
            if (n, fraction) in paper.TABLE_S4_DISAGREES_WITH_S3:
                continue
            s4 = paper.TABLE_S4_PERCENT[n][fraction]
            tolerance = HALF_DIGIT * factor + HALF_DIGIT
            assert s4.mean == pytest.approx(s3.mean * factor, abs=tolerance), (n, fraction)
            assert s4.sd == pytest.approx(s3.sd * factor, abs=tolerance), (n, fraction)
            checked += 1
    assert checked == 32


def test_the_40_percent_cells_read_with_a_dropped_zero_match_table_s4() -> None:
    for n in (100, 1000):
        converted = paper.speed_to_percent_diameter_per_cycle(paper.TABLE_S3_MM_S[n][0.4].mean)
        assert converted == pytest.approx(paper.TABLE_S4_PERCENT[n][0.4].mean, abs=HALF_DIGIT)


def test_the_cells_where_s4_disagrees_with_s3_really_do() -> None:
    factor = paper.speed_to_percent_diameter_per_cycle(1.0)
    tolerance = HALF_DIGIT * factor + HALF_DIGIT
    for n, fraction in paper.TABLE_S4_DISAGREES_WITH_S3:
        s3 = paper.TABLE_S3_MM_S[n][fraction]
        s4 = paper.TABLE_S4_PERCENT[n][fraction]
        off_mean = abs(s4.mean - s3.mean * factor) > tolerance
        off_sd = abs(s4.sd - s3.sd * factor) > tolerance
        assert off_mean or off_sd, (n, fraction)


def test_tables_s5_and_s6_agree_and_their_gaps_are_fractions_of_the_dpd() -> None:
    assert paper.TABLE_S5_DPD_CM.keys() == paper.TABLE_S6_DPD_DIAMETERS.keys()
    for n, dpd_cm in paper.TABLE_S5_DPD_CM.items():
        diameters = paper.TABLE_S6_DPD_DIAMETERS[n]
        assert dpd_cm == pytest.approx(diameters * paper.D_MIN_M * 100, rel=2e-3), n
        for fraction, cm, gap in zip(
            paper.GAP_FRACTIONS,
            paper.TABLE_S5_GAP_CM[n],
            paper.TABLE_S6_GAP_DIAMETERS[n],
            strict=True,
        ):
            assert cm == pytest.approx(fraction * dpd_cm, abs=0.006), (n, fraction)
            # Table S6 was computed from the unrounded DPD: allow for its rounding too.
            assert gap == pytest.approx(fraction * diameters, abs=0.006 * (1 + fraction)), (
                n,
                fraction,
            )


@pytest.mark.parametrize(
    ("n", "optimum"),
    [(3, 1 + 2 / math.sqrt(3)), pytest.param(10, 3.813026, marks=pytest.mark.slow)],
)
def test_small_packings_reach_the_known_optima(n: int, optimum: float) -> None:
    assert compute_densest_packing(n) == pytest.approx(optimum, abs=2e-4)


@pytest.mark.slow
def test_the_generated_table_holds_what_the_computation_gives() -> None:
    assert DPD_DIAMETERS[10] == compute_densest_packing(10)
    assert densest_packing_diameters(10) == DPD_DIAMETERS[10]


def test_our_dpd_is_within_a_fifth_of_a_percent_of_table_s6_at_every_size() -> None:
    for n, published in paper.TABLE_S6_DPD_DIAMETERS.items():
        assert densest_packing_diameters(n) == pytest.approx(published, rel=2e-3), n


def test_relaxing_the_lattice_never_makes_a_packing_larger() -> None:
    for n in DPD_DIAMETERS:
        assert DPD_DIAMETERS[n] <= hexagonal_lattice_diameters(n) + 1e-4


def test_the_dpd_in_metres_uses_the_minimum_diameter() -> None:
    assert densest_packing_diameter_m(100) == pytest.approx(11.0866 * 0.155)
    with pytest.raises(ValueError, match="at least one"):
        densest_packing_diameters(0)
