"""Properties of the firmware's S_n estimators (SI section S4) against independent Python."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from particlebot.firmware.native import estimate
from particlebot.protocol import PARAM_SPECS, Method, Param
from tests.firmware.conftest import (
    DIAMETER_M,
    LAMP_HEIGHT_M,
    REF_DISTANCE_M,
    REF_VALUE,
    reading_at,
    reading_on_floor,
)

METHODS = list(Method)
ground_distances = st.lists(
    st.floats(min_value=0.0, max_value=3.0, allow_nan=False), min_size=1, max_size=14
)


def others_than(values: list[int], i: int) -> list[int]:
    return values[:i] + values[i + 1 :]


@settings(max_examples=150, deadline=None)
@given(distances=ground_distances, method=st.sampled_from(METHODS))
def test_s_n_never_decreases_with_distance_to_the_light(
    distances: list[float], method: Method
) -> None:
    readings = [reading_on_floor(d) for d in distances]
    ranked = sorted(
        (d, estimate(method, v, others_than(readings, i)))
        for i, (d, v) in enumerate(zip(distances, readings, strict=True))
    )
    s_values = [s for _, s in ranked]
    assert all(1 <= s <= 255 for s in s_values)
    assert s_values == sorted(s_values), ranked


@settings(max_examples=300, deadline=None)
@given(
    method=st.integers(0, 255),
    own=st.integers(0, 0xFFFF),
    others=st.lists(st.integers(0, 0xFFFF), max_size=40),
    params=st.tuples(*[st.integers(-(2**31), 2**31 - 1)] * 5),
)
def test_estimate_accepts_any_input_and_answers_in_range(
    method: int, own: int, others: list[int], params: tuple[int, int, int, int, int]
) -> None:
    ref_distance, ref_value, diameter, tolerance, groups = params
    s = estimate(
        method,
        own,
        others,
        ref_distance_mm=ref_distance,
        ref_value=ref_value,
        diameter_mm=diameter,
        count_tolerance=tolerance,
        groups=groups,
    )
    if method in set(Method):
        assert 1 <= s <= 255
    else:
        assert s == 0


def stronger_levels(own: int, others: list[int], tolerance: int) -> int:
    """Algorithm 4 over the stronger readings in descending order (the brief's fixed order)."""
    levels: list[int] = []
    for v in sorted((v for v in others if v > own), reverse=True):
        if not levels or levels[-1] - v > tolerance:
            levels.append(v)
    return len(levels)


@settings(max_examples=300, deadline=None)
@given(
    own=st.integers(0, 1023),
    others=st.lists(st.integers(0, 1023), max_size=32),
    tolerance=st.integers(0, 200),
)
def test_counting_gives_one_plus_the_distinct_stronger_levels(
    own: int, others: list[int], tolerance: int
) -> None:
    expected = min(255, 1 + stronger_levels(own, others, tolerance))
    s = estimate(Method.COUNTING, own, others, count_tolerance=tolerance)
    assert s == expected
    assert estimate(Method.COUNTING, own, list(reversed(others)), count_tolerance=tolerance) == s


def direct_index(v: int, r_x: int, v_x: int, diameter: int) -> float | None:
    """Eqs. 14-16 in floating point: D_n / D, or None at the ends of the ADC range."""
    if v <= 0 or v >= 1023:
        return None
    r_n2 = v_x * (1023 - v) / (v * (1023 - v_x)) * r_x**2  # eq. 14
    d_n = math.sqrt(max(0.0, r_n2 - r_x**2))  # eq. 15
    return d_n / diameter  # eq. 16


@settings(max_examples=400, deadline=None)
@given(
    v=st.integers(0, 1100),
    r_x=st.integers(PARAM_SPECS[Param.REF_DISTANCE_MM].min, PARAM_SPECS[Param.REF_DISTANCE_MM].max),
    v_x=st.integers(PARAM_SPECS[Param.REF_VALUE].min, PARAM_SPECS[Param.REF_VALUE].max),
    diameter=st.integers(PARAM_SPECS[Param.DIAMETER_MM].min, PARAM_SPECS[Param.DIAMETER_MM].max),
)
def test_direct_estimation_follows_eqs_14_to_16(v: int, r_x: int, v_x: int, diameter: int) -> None:
    s = estimate(Method.DIRECT, v, [], ref_distance_mm=r_x, ref_value=v_x, diameter_mm=diameter)
    index = direct_index(v, r_x, v_x, diameter)
    if index is None:
        assert s == (255 if v <= 0 else 1)
        return
    expected = min(255, 1 + math.floor(index + 0.5))
    if abs(index % 1 - 0.5) < 1e-6:  # a tie within float error: either neighbour
        assert s in (expected - 1, expected)
    else:
        assert s == expected


def test_direct_estimation_with_the_papers_reference_counts_diameters_from_under_the_lamp() -> None:
    for k in range(8):
        v = reading_on_floor(k * DIAMETER_M)
        assert estimate(Method.DIRECT, v, []) == k + 1
    assert reading_on_floor(0.0) == REF_VALUE and LAMP_HEIGHT_M == REF_DISTANCE_M


def group_count(v_max: int, v_min: int, groups: int) -> int:
    """N_w: GROUPS, or with GROUPS 0 the rows of the group toward the lamp: method A's S_n (eqs.
    14-16, checked on its own above) of the weakest reading less that of the strongest, plus 1."""
    if groups > 0:
        return groups
    return estimate(Method.DIRECT, v_min, []) - estimate(Method.DIRECT, v_max, []) + 1


@settings(max_examples=300, deadline=None)
@given(
    own=st.integers(0, 1023),
    others=st.lists(st.integers(0, 1023), max_size=32),
    groups=st.integers(0, 64),
)
def test_linear_estimation_follows_eqs_17_and_18(own: int, others: list[int], groups: int) -> None:
    group = [own, *others]
    v_max, v_min = max(group), min(group)
    n_w = group_count(v_max, v_min, groups)
    if not others or v_max == v_min:
        expected = 1
    else:
        delta = Fraction(v_max - v_min, n_w)  # eq. 17
        expected = 1 + min(math.floor((v_max - own) / delta), n_w - 1)  # eq. 18, 1-based
    assert estimate(Method.LINEAR, own, others, groups=groups) == expected


def nonlinear_groups(own: int, others: list[int], groups: int) -> tuple[float, int] | None:
    """Eqs. 29-30 in floating point: (N_w rho, N_w), or None for a degenerate group. Readings
    of 0 count as 1 and readings above full scale as 1023 (a distance of 0)."""

    def root(v: int) -> float:
        v = min(max(v, 1), 1023)
        return math.sqrt((1023 - v) / v)

    group = [own, *others]
    a, b, c = root(max(group)), root(min(group)), root(own)
    if not others or b <= a:
        return None
    clamped = [min(max(v, 1), 1023) for v in group]
    n_w = group_count(max(clamped), min(clamped), groups)
    return n_w * (c - a) / (b - a), n_w  # eqs. 29 and 30


# Groups of close readings are where rounding the roots shows: a base and small offsets.
close_groups = st.tuples(st.integers(0, 1023), st.sampled_from([2, 4, 10, 40])).flatmap(
    lambda t: st.lists(
        st.integers(0, t[1]).map(lambda k: min(1023, t[0] + k)), min_size=2, max_size=64
    )
)


@pytest.mark.slow
@settings(max_examples=600, deadline=None)
@given(
    readings=st.one_of(
        close_groups,
        st.lists(st.integers(0, 1100), min_size=2, max_size=64),
        st.tuples(st.integers(1, 1000), st.integers(1, 4), st.integers(2, 64)).map(
            lambda t: [min(1023, t[0] + t[1] * i) for i in range(t[2])]
        ),
    ),
    pick=st.integers(0, 63),
    groups=st.sampled_from([0, 64, 33, 7, 1]) | st.integers(0, 64),
)
def test_nonlinear_estimation_equals_eqs_29_and_30_off_group_boundaries(
    readings: list[int], pick: int, groups: int
) -> None:
    own = readings[pick % len(readings)]
    others = readings[: pick % len(readings)] + readings[pick % len(readings) + 1 :]
    s = estimate(Method.NONLINEAR, own, others, groups=groups)
    exact = nonlinear_groups(own, others, groups)
    if exact is None:
        assert s == 1
        return
    x, n_w = exact
    assume(abs(x - round(x)) >= 1e-3)  # within 1e-3 of a group boundary either side will do
    assert s == 1 + min(math.floor(x), n_w - 1)


def test_with_groups_0_a_blobs_rows_move_together() -> None:
    # Two particles a few centimetres apart, two one diameter further, one two diameters further:
    # methods B and C give each row one S_n, as method A does (the SI's N_w: the body's length
    # in particles toward the lamp, eqs. 19-22).
    ground = [0.50, 0.53, 0.655, 0.68, 0.81]
    readings = [reading_on_floor(d) for d in ground]
    for method in (Method.LINEAR, Method.NONLINEAR):
        s_n = [estimate(method, v, others_than(readings, k)) for k, v in enumerate(readings)]
        assert s_n == [1, 1, 2, 2, 3]


def test_nonlinear_estimation_places_a_line_of_particles_exactly() -> None:
    # Fig. S7's planar field (the lamp level with the photocells): five particles at (K + n) D
    # from the lamp, K = 2, in N_w = 5 groups. (GROUPS 0 would count rows with the lamp at the
    # reference height above them, as method A does.)
    readings = [reading_at((2 + k) * DIAMETER_M) for k in range(5)]
    for k, v in enumerate(readings):
        assert estimate(Method.NONLINEAR, v, others_than(readings, k), groups=5) == k + 1
    # The same line on the floor under a lamp at the reference height, GROUPS 0: its rank.
    readings = [reading_on_floor((2 + k) * DIAMETER_M) for k in range(5)]
    for k, v in enumerate(readings):
        assert estimate(Method.NONLINEAR, v, others_than(readings, k)) == k + 1
