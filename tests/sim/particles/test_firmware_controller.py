"""The `firmware` controller: radius against a native particle, noise, phototaxis, the deep wave."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from particlebot.firmware.native import NativeParticle
from particlebot.protocol import Intensity, Method, Param, ParamResult, Start, State
from particlebot.sim.particles.model.estimation import EstimationParams
from particlebot.sim.particles.model.firmware import (
    FirmwareController,
    FirmwareSettings,
    noisy_readings,
)
from particlebot.sim.particles.model.static_view import StaticView
from particlebot.sim.world.light import LightField
from tests.firmware.conftest import DIAMETER_M, Bench, reading_on_floor

WORLD_STEP_MS = 10


@dataclass
class Run:
    """A run to replay on both sides: the settings, and each particle's readings from a given
    moment on (particle 0 is the native one; the others only broadcast)."""

    settings: FirmwareSettings
    readings: list[tuple[int, list[int]]]  # (ms after START, readings of every particle)
    duration_ms: int
    expected_s_n: list[int] = field(default_factory=list)  # particle 0's, round by round


def store_settings(bench: Bench, settings: FirmwareSettings) -> None:
    """The particle's stored parameters as the run's settings have them."""
    e = settings.estimation
    for param, value in (
        (Param.WAVE_SIZE, settings.wave_size_param),
        (Param.ROUND_MS, settings.round_ms),
        (Param.REF_DISTANCE_MM, e.ref_distance_mm),
        (Param.REF_VALUE, e.ref_value),
        (Param.DIAMETER_MM, e.diameter_mm),
        (Param.COUNT_TOLERANCE, e.count_tolerance),
        (Param.GROUPS, e.groups),
    ):
        assert bench.set_param(param, value).result == ParamResult.OK


def replay(run: Run) -> tuple[float, list[int], float]:
    """Drives a NativeParticle through START and the controller through a StaticView of the
    same readings, comparing their radii every 10 ms; returns the largest difference (um), the
    S_n the native particle reported after each of its rounds and the share of time it moved."""
    first = run.readings[0][1]
    bench = Bench(NativeParticle(rng_seed=99), adc=first[0])
    store_settings(bench, run.settings)
    start_ms = bench.now
    view = StaticView(np.zeros(len(first)), np.zeros(len(first)), np.array(first, dtype=float))
    controller = FirmwareController(replace(run.settings, start_s=start_ms / 1000))
    controller.bind(view.count, np.random.default_rng(0))
    out = np.empty(view.count)
    s = run.settings
    bench.send(
        Start(
            run_id=1,
            method=s.method,
            cycle_steps=s.cycle_steps,
            wave_size=s.wave_size,
            update_interval_s=s.update_interval_s,
            phototaxis=int(s.phototaxis),
        )
    )
    changes = list(run.readings[1:])
    worst = 0.0
    moving = 0
    s_n_seen: list[int] = []
    round_no, round_start, sent = 0, start_ms, False
    model_round, broadcasting = 0, np.ones(view.count, dtype=bool)
    state = State.ESTIMATING
    while bench.now - start_ms < run.duration_ms:
        bench.advance(WORLD_STEP_MS, step_ms=WORLD_STEP_MS)
        now = bench.now
        if changes and now - start_ms >= changes[0][0]:
            view.readings = np.array(changes.pop(0)[1], dtype=float)
            bench.particle.set_adc([int(view.readings[0])] * 6)
        status = bench.status()
        if status.state == State.ESTIMATING and state != State.ESTIMATING:
            round_no, round_start, sent = round_no + 1, now, False
        if state == State.ESTIMATING and status.state != State.ESTIMATING:
            s_n_seen.append(status.s_n)
        state = State(status.state)
        if state == State.ESTIMATING and not sent and now - round_start >= 100:
            # The others' broadcasts of this round, from ids 1, 2, ...: those that were still
            # running when it began (a particle DONE with phototaxis falls silent).
            for sender in range(1, view.count):
                if not broadcasting[sender]:
                    continue
                reading = int(view.readings[sender])
                message = Intensity(run_id=1, round=round_no, repeat=0, intensity=reading)
                bench.send(message, sender=sender)
            sent = True
        view.t = now / 1000
        before = ~controller.done
        controller.command(view, out)
        if controller.round != model_round:
            model_round, broadcasting = controller.round, before
        worst = max(worst, abs(out[0] * 1e6 - bench.particle.radius_um))
        moving += bench.particle.radius_um > view.r_min * 1e6 + 0.5
        if state != State.DONE:
            assert controller.round == round_no, now
    assert controller.done[0] == (state == State.DONE)
    bench.particle.close()
    return worst, s_n_seen, moving * WORLD_STEP_MS / run.duration_ms


def floor_readings(ranks: list[int]) -> list[int]:
    """Readings of particles ranks[i] - 1 diameters along the floor from under the lamp."""
    return [reading_on_floor((rank - 1) * DIAMETER_M) for rank in ranks]


RUNS = {
    # Method A alone, S_n 9, 2 and 6 at the protocol's shortest interval; N = 3 wraps S_n 9.
    "A T=3s N=3 10s": Run(
        FirmwareSettings(method=Method.DIRECT, cycle_steps=150, wave_size=3, update_interval_s=10),
        [(0, floor_readings([9])), (14_000, floor_readings([2])), (25_000, floor_readings([6]))],
        duration_ms=45_000,
        expected_s_n=[9, 9, 2, 6, 6],
    ),
    # Method D among 8, automatic N (the group), the particle moving up and down the ranks.
    "D T=1.5s N=auto 20s": Run(
        FirmwareSettings(method=Method.COUNTING, cycle_steps=75, update_interval_s=20),
        [
            (0, floor_readings([5, 1, 2, 3, 4, 6, 7, 8])),
            (30_000, floor_readings([8, 1, 2, 3, 4, 5, 6, 7])),
            (50_000, floor_readings([1, 2, 3, 4, 5, 6, 7, 8])),
        ],
        duration_ms=75_000,
        expected_s_n=[5, 5, 8, 1],
    ),
    # Method C, T = 6 s, N = 2, readings as a plane's inverse square (Fig. S7).
    "C T=6s N=2 10s": Run(
        FirmwareSettings(
            method=Method.NONLINEAR, cycle_steps=300, wave_size=2, update_interval_s=10
        ),
        [(0, floor_readings([6, 1, 2, 3, 4, 5])), (20_000, floor_readings([3, 1, 2, 4, 5, 6]))],
        duration_ms=50_000,
    ),
    # Method B with 8 groups over 5 particles and an odd T.
    "B T=2s N=auto 15s": Run(
        FirmwareSettings(
            method=Method.LINEAR,
            cycle_steps=100,
            update_interval_s=15,
            estimation=EstimationParams(groups=8),
        ),
        [(0, [700, 900, 800, 600, 500]), (20_000, [520, 900, 800, 600, 500])],
        duration_ms=60_000,
        expected_s_n=[5, 5, 8, 8],
    ),
    # Phototaxis: brighter for two rounds, then not: DONE, contracted for good.
    "D phototaxis": Run(
        FirmwareSettings(
            method=Method.COUNTING,
            cycle_steps=75,
            wave_size=2,
            update_interval_s=10,
            phototaxis=True,
        ),
        [(0, [600, 900, 700]), (5_000, [650, 900, 700]), (16_000, [660, 900, 700])],
        duration_ms=60_000,
    ),
}


@pytest.mark.parametrize("name", list(RUNS))
def test_radius_matches_a_native_particle_through_several_epochs(name: str) -> None:
    run = RUNS[name]
    worst, s_n_seen, moving = replay(run)
    assert worst <= 1.0, f"{name}: {worst:.3f} um"
    assert moving > 0.05
    if run.expected_s_n:
        assert s_n_seen == run.expected_s_n


@settings(max_examples=8, deadline=None)
@given(
    method=st.sampled_from([Method.DIRECT, Method.COUNTING]),
    cycle_steps=st.sampled_from([10, 37, 75, 150]),
    wave_size=st.integers(0, 6),
    interval_s=st.sampled_from([10, 13]),
    ranks=st.lists(st.integers(1, 12), min_size=3, max_size=3),
)
def test_radius_matches_a_native_particle_for_any_schedule(
    method: Method, cycle_steps: int, wave_size: int, interval_s: int, ranks: list[int]
) -> None:
    settings_ = FirmwareSettings(
        method=method, cycle_steps=cycle_steps, wave_size=wave_size, update_interval_s=interval_s
    )
    n_wave = wave_size or (settings_.wave_size_param if method is Method.DIRECT else 9)
    epoch = max(interval_s * 1000, settings_.round_ms + (n_wave + 2) * cycle_steps * 10)
    # Particle 0 changes rank halfway through each epoch; eight others sit at ranks 1..8.
    readings = [
        (k * epoch + (epoch // 2 if k else 0), floor_readings([rank, *range(1, 9)]))
        for k, rank in enumerate(ranks)
    ]
    worst, _, _ = replay(Run(settings_, readings, duration_ms=3 * epoch + epoch // 2))
    assert worst <= 1.0


def test_a_phototaxis_run_ends_contracted_once_the_light_stops_increasing() -> None:
    run = RUNS["D phototaxis"]
    view = StaticView(np.zeros(3), np.zeros(3), np.array(run.readings[0][1], dtype=float))
    controller = FirmwareController(run.settings)
    controller.bind(3, np.random.default_rng(0))
    out = np.empty(3)
    for t_ms in range(0, 60_000, WORLD_STEP_MS):
        for at, readings in run.readings:
            if t_ms == at:
                view.readings = np.array(readings, dtype=float)
        view.t = t_ms / 1000
        controller.command(view, out)
    # Particles 1 and 2 never got brighter after the first round; particle 0 stopped later.
    assert controller.done.tolist() == [True, True, True]
    assert (out == view.r_min).all()


def test_every_particle_of_a_deep_wave_cycles_in_every_epoch() -> None:
    # 400 particles in a line from the lamp (S_n 1..255 by method A), N = 5, 10 s epochs: with
    # eq. 5's t_I taken literally only the first few ranks would ever move.
    count = 400
    ground = np.arange(count, dtype=np.float64) * 2 * 0.0775
    readings = np.array([reading_on_floor(d) for d in ground], dtype=float)
    view = StaticView(ground, np.zeros(count), readings)
    settings = FirmwareSettings(method=Method.DIRECT, wave_size=5, update_interval_s=10)
    controller = FirmwareController(settings)
    controller.bind(count, np.random.default_rng(0))
    out = np.empty(count)
    moved = np.zeros((3, count), dtype=bool)
    epoch = 0
    t_ms = 0
    while epoch < 3:
        view.t = t_ms / 1000
        controller.command(view, out)
        epoch = controller.round
        if epoch < 3:
            moved[epoch] |= out > view.r_min
        t_ms += WORLD_STEP_MS
    assert controller.s_n.max() == 255
    assert moved.all()


def test_phase_runs_from_0_to_1_in_a_cycle_and_is_nan_otherwise() -> None:
    view = StaticView(np.zeros(3), np.zeros(3), np.array(floor_readings([1, 2, 3]), dtype=float))
    view.alive[2] = False
    settings = FirmwareSettings(method=Method.DIRECT, cycle_steps=100, wave_size=3)
    controller = FirmwareController(settings)
    controller.bind(3, np.random.default_rng(0))
    out = np.empty(3)
    common_start = settings.round_ms
    for t_ms, expected in [
        (common_start - 10, [math.nan, math.nan, math.nan]),
        (common_start + 500, [0.25, math.nan, math.nan]),
        (common_start + 1500, [0.75, 0.25, math.nan]),  # particle 2 would be at 0: not acting
        (common_start + 2000, [math.nan, 0.5, math.nan]),
    ]:
        view.t = t_ms / 1000
        controller.command(view, out)
        assert np.allclose(controller.phase(view), expected, equal_nan=True), t_ms


def test_noise_gives_distance_estimates_the_asked_spread_in_diameters() -> None:
    # The paper's lamp and calibration: 28 cm up, reading 980 under it, so eq. 14's distance is
    # the true one and a reading's error maps onto the ground distance exactly.
    light = LightField()
    rng = np.random.default_rng(3)
    count = 40_000
    ground = rng.uniform(0.8, 3.0, count)
    readings = np.array([light.reading(d, 0.0) for d in ground])
    params = EstimationParams()
    diameter = 2 * 0.0775
    for sigma in (0.25, 1.0, 2.0):
        noisy = noisy_readings(readings, sigma * diameter, rng, params, 1023)
        implied = np.array([light.distance_for_reading(v) for v in noisy])
        error = np.sqrt(np.maximum(implied**2 - light.lamp.height**2, 0)) - ground
        assert abs(error.std() / diameter - sigma) < 0.03 * sigma
        assert abs(error.mean()) < 0.03 * diameter


def test_method_a_ranks_spread_by_the_noise_once_rounded_to_counts() -> None:
    # End to end through the controller: S_n under noise of 1 diameter against S_n without,
    # for particles far enough out that a reading count is worth well under a diameter.
    count = 20_000
    rng = np.random.default_rng(5)
    ground = rng.uniform(0.6, 1.6, count)
    readings = np.array([reading_on_floor(d) for d in ground], dtype=float)
    view = StaticView(ground, np.zeros(count), readings)
    ranks = []
    for noise in (0.0, 1.0):
        controller = FirmwareController(
            FirmwareSettings(method=Method.DIRECT, noise_diameters=noise)
        )
        controller.bind(count, np.random.default_rng(11))
        controller.command(view, np.empty(count))
        ranks.append(controller.s_n)
    spread = (ranks[1] - ranks[0]).std()
    # Gaussian of 1 diameter, rounded to whole ranks: sqrt(1 + 1/12) ~ 1.04, plus quantisation.
    assert 0.95 < spread < 1.2


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"cycle_steps": 5}, "cycle_steps = 5 is outside 10..3000"),
        ({"wave_size": 256}, "wave_size = 256 is outside 0..255"),
        ({"update_interval_s": 9}, "update_interval_s = 9 is outside 10..3600"),
        ({"noise_diameters": -0.5}, "noise_diameters must be a number 0..1e+06, not -0.5"),
        ({"noise_diameters": math.nan}, "noise_diameters must be a number 0..1e+06, not nan"),
        ({"start_s": math.inf}, "start_s must be a number 0..1e+08, not inf"),
        ({"method": 2}, "method must be one of DIRECT, LINEAR, NONLINEAR, COUNTING"),
    ],
)
def test_settings_outside_the_firmwares_ranges_are_refused(
    change: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        replace(FirmwareSettings(), **change)  # type: ignore[arg-type]


def test_estimation_parameters_outside_their_ranges_are_refused() -> None:
    with pytest.raises(ValueError, match=re.escape("ref_value = 1023 is outside 1..1022")):
        EstimationParams(ref_value=1023)
