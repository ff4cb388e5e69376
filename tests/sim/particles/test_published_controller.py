"""The `published` controller: its profile, phases from distance, noise, updates, fast path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController, PublishedSettings
from particlebot.sim.particles.model.static_view import StaticView

R_MIN = 0.0775
R_MAX = 0.1175
DT = 0.01


def _view(distances: np.ndarray) -> StaticView:
    """Particles on the x axis at these distances from a lamp at the origin, all lit."""
    return StaticView(distances, np.zeros_like(distances), np.full(distances.shape, 500.0))


def _bound(settings: PublishedSettings, view: StaticView, seed: int = 0) -> PublishedController:
    controller = PublishedController(settings)
    controller.bind(view.count, np.random.default_rng(seed))
    return controller


def test_a_cycle_expands_linearly_contracts_and_rests() -> None:
    view = _view(np.array([1.0]))
    controller = _bound(PublishedSettings(phase_noise=0.0), view)
    out = np.empty(1)
    radii = []
    for step in range(1200):
        view.t = step * DT
        controller.command(view, out)
        radii.append(out[0])
    r = np.array(radii)
    t = np.arange(1200) * DT
    rising = t < 2.0
    falling = (t >= 2.0) & (t < 4.0)
    assert r[rising] == pytest.approx(R_MIN + (R_MAX - R_MIN) * t[rising] / 2.0)
    assert r[falling] == pytest.approx(R_MAX - (R_MAX - R_MIN) * (t[falling] - 2.0) / 2.0)
    assert np.isnan(r[t >= 4.0]).all()  # the rest: the servo holds


def test_phases_lag_two_seconds_per_contracted_diameter_from_the_nearest() -> None:
    distances = 3.0 + np.arange(5) * 2 * R_MIN
    view = _view(distances[::-1].copy())
    controller = _bound(PublishedSettings(phase_noise=0.0), view)
    controller.command(view, np.empty(5))
    assert controller.phases == pytest.approx([-8.0, -6.0, -4.0, -2.0, 0.0])


def test_particles_that_may_not_act_do_not_set_the_nearest_distance() -> None:
    view = _view(np.array([1.0, 1.0 + 2 * R_MIN, 1.0 + 4 * R_MIN]))
    view.alive[0] = False
    controller = _bound(PublishedSettings(phase_noise=0.0), view)
    controller.command(view, np.empty(3))
    assert controller.phases[1:] == pytest.approx([0.0, -2.0])


@pytest.mark.parametrize(
    ("settings", "expected_sd"),
    [
        (PublishedSettings(), 0.3 * 2.0),  # phase noise: 0.3 rise periods
        (PublishedSettings(phase_noise=0.0, noise_diameters=1.0), 2.0),  # 1 diameter = 2 s
        (PublishedSettings(phase_noise=0.0, noise_diameters=0.5), 1.0),
    ],
)
def test_phase_and_distance_noise_have_their_standard_deviations(
    settings: PublishedSettings, expected_sd: float
) -> None:
    view = _view(np.full(20000, 5.0))
    controller = _bound(settings, view, seed=3)
    controller.command(view, np.empty(view.count))
    assert np.std(controller.phases) == pytest.approx(expected_sd, rel=0.03)


@pytest.mark.parametrize("cycles", [1, 3])
def test_phases_change_only_every_n_cycles(cycles: int) -> None:
    view = _view(np.linspace(1.0, 2.0, 50))
    controller = _bound(PublishedSettings(update_cycles=cycles), view)
    out = np.empty(view.count)
    changes = []
    last = None
    for step in range(0, 8000):
        view.t = step * DT
        controller.command(view, out)
        if last is not None and not np.array_equal(last, controller.phases):
            changes.append(round(view.t, 6))
        last = controller.phases
    period = 12.0 * cycles
    assert changes == [period * k for k in range(1, math.ceil(80.0 / period))]


def test_commands_ahead_equal_commands_step_by_step() -> None:
    rng = np.random.default_rng(9)
    distances = rng.uniform(1.0, 3.0, 40)
    ahead_view, step_view = _view(distances), _view(distances)
    ahead = _bound(PublishedSettings(), ahead_view, seed=5)
    stepped = _bound(PublishedSettings(), step_view, seed=5)
    rows = []
    step = 0
    while step < 3000:
        ahead_view.t = step * DT
        block = np.empty((700, 40))
        done = ahead.command_ahead(ahead_view, DT, block)
        assert 1 <= done <= 700
        rows.append(block[:done])
        step += done
    by_step = np.empty((step, 40))
    for k in range(step):
        step_view.t = k * DT
        stepped.command(step_view, by_step[k])
    assert np.array_equal(np.concatenate(rows), by_step, equal_nan=True)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"rise_s": 0.0},
        {"nx": 0},
        {"update_cycles": 1.5},
        {"phase_noise": -1.0},
        {"noise_diameters": math.nan},
    ],
)
def test_bad_settings_are_refused(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError):
        PublishedSettings(**kwargs)  # type: ignore[arg-type]
