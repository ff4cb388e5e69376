"""The vectorised S_n and schedule of the `firmware` controller against the native firmware."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.firmware import native
from particlebot.protocol import PARAM_SPECS, Method, Param
from particlebot.sim.particles.model.estimation import EstimationParams, GroupEstimator
from particlebot.sim.particles.model.firmware import FirmwareSettings, plan_epochs


def in_spec(param: Param) -> st.SearchStrategy[int]:
    spec = PARAM_SPECS[param]
    return st.integers(spec.min, spec.max)


estimation_params = st.builds(
    EstimationParams,
    ref_distance_mm=in_spec(Param.REF_DISTANCE_MM),
    ref_value=in_spec(Param.REF_VALUE),
    diameter_mm=in_spec(Param.DIAMETER_MM),
    count_tolerance=in_spec(Param.COUNT_TOLERANCE),
    groups=st.sampled_from([0, 0, 1, 64]) | in_spec(Param.GROUPS),
)
# Readings a particle can broadcast (0 when its sensors are faulty, else 1..1022), spread out or
# bunched, where the integer arithmetic of methods B-D is at its finest.
bunched = st.tuples(st.integers(0, 1022), st.sampled_from([2, 12, 60])).flatmap(
    lambda t: st.lists(st.integers(0, t[1]).map(lambda k: min(1022, t[0] + k)), max_size=40)
)
groups_of_readings = st.one_of(st.lists(st.integers(0, 1023), max_size=40), bunched).filter(
    lambda g: len(g) > 0
)


def native_estimate(method: Method, readings: list[int], i: int, p: EstimationParams) -> int:
    return native.estimate(
        method,
        readings[i],
        readings[:i] + readings[i + 1 :],
        ref_distance_mm=p.ref_distance_mm,
        ref_value=p.ref_value,
        diameter_mm=p.diameter_mm,
        count_tolerance=p.count_tolerance,
        groups=p.groups,
    )


@settings(max_examples=400, deadline=None)
@given(method=st.sampled_from(list(Method)), readings=groups_of_readings, p=estimation_params)
def test_every_members_s_n_equals_the_native_estimators(
    method: Method, readings: list[int], p: EstimationParams
) -> None:
    # The model's radio: each member hears every other member of the group.
    vectorised = GroupEstimator(p, native.firmware_constants()).estimate(method, np.array(readings))
    expected = [native_estimate(method, readings, i, p) for i in range(len(readings))]
    assert vectorised.tolist() == expected


@pytest.mark.parametrize("method", [Method.LINEAR, Method.NONLINEAR, Method.COUNTING])
def test_s_n_in_a_large_group_equals_the_native_estimators(method: Method) -> None:
    constants = native.firmware_constants()
    rng = np.random.default_rng(7)
    readings = rng.integers(300, 1000, 3000).tolist()
    p = EstimationParams()
    vectorised = GroupEstimator(p, constants).estimate(method, np.array(readings))
    # The brightest, the dimmest, and particles just below the brightest where N_w matters.
    order = np.argsort(readings)
    picks = [*order[:3], *order[-40:], *rng.integers(0, len(readings), 5)]
    for i in picks:
        assert vectorised[i] == native_estimate(method, readings, int(i), p), i


def test_intensities_follow_the_firmware_sampler() -> None:
    # Each reading rounds to a count; six sensors reading 0 or full scale are all faulty.
    readings = [0.0, 0.4, 0.6, 511.5, 1022.49, 1022.5, 1023.0, 2000.0]
    estimator = GroupEstimator(EstimationParams(), native.firmware_constants())
    got = estimator.intensities(np.array(readings)).tolist()
    for reading, intensity in zip(readings, got, strict=True):
        with native.NativeParticle() as particle:
            particle.set_adc([min(1023, round(reading))] * 6)
            particle.tick(100)
            assert particle.status().intensity == intensity, reading


@settings(max_examples=400, deadline=None)
@given(
    method=st.sampled_from(list(Method)),
    cycle_steps=in_spec(Param.CYCLE_STEPS),
    wave_size=st.integers(0, 255),
    wave_size_param=in_spec(Param.WAVE_SIZE),
    update_interval_s=in_spec(Param.UPDATE_INTERVAL_S),
    round_ms=in_spec(Param.ROUND_MS),
    s_n=st.integers(1, 255),
    group_size=st.integers(1, 255),
)
def test_epoch_plans_equal_the_firmwares(
    method: Method,
    cycle_steps: int,
    wave_size: int,
    wave_size_param: int,
    update_interval_s: int,
    round_ms: int,
    s_n: int,
    group_size: int,
) -> None:
    settings_ = FirmwareSettings(
        method=method,
        cycle_steps=cycle_steps,
        wave_size=wave_size,
        wave_size_param=wave_size_param,
        update_interval_s=update_interval_s,
        round_ms=round_ms,
    )
    plans = plan_epochs(
        settings_, np.array([s_n]), group_size, native.firmware_constants().servo_step_ms
    )
    expected = native.plan_epoch(
        method,
        cycle_steps=cycle_steps,
        wave_size=wave_size,
        wave_size_param=wave_size_param,
        update_interval_ms=update_interval_s * 1000,
        round_ms=round_ms,
        s_n=s_n,
        group_size=group_size,
    )
    got = (int(plans.first_cycle_ms[0]), plans.pause_ms, plans.epoch_ms)
    assert got == (expected.first_cycle_ms, expected.pause_ms, expected.epoch_ms)
