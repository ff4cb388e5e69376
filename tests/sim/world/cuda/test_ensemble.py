"""Ensembles: many worlds in one launch take each its own path, the one it takes alone; and a
swarm whose pair sums add in another order than the CPU's moves as the CPU's does, statistically."""

from __future__ import annotations

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController, PublishedSettings
from particlebot.sim.world import Arena, DeadParticles, PassiveObject, Rect, World
from particlebot.sim.world.cuda.ensemble import Ensemble
from particlebot.sim.world.light import Lamp
from tests.sim.world.conftest import R_MIN, cluster


def _worlds(device: str) -> list[World]:
    """Three different setups: a pair, a pair with a passive object and a wall, a dying trio."""
    gap = 2 * R_MIN + 0.004
    return [
        World([0.0, gap], [0.0, 0.0], controller=PublishedController(), seed=1, device=device),
        World([0.0, gap], [0.0, 0.01], controller=PublishedController(), seed=2, device=device,
              objects=[PassiveObject(x=-gap, y=0.0, radius=R_MIN)],
              arena=Arena(rects=(Rect(0.5, 0.6, -1.0, 1.0),))),
        World([0.0, gap, 2 * gap], [0.0, 0.0, 0.0], controller=PublishedController(), seed=3,
              device=device, dead=DeadParticles(1, 0.03, detach=True)),
    ]  # fmt: skip


def test_an_ensemble_steps_each_world_as_it_steps_alone_and_as_the_cpu_does() -> None:
    ensemble = Ensemble(_worlds("cpu"))
    ensemble.step(8)
    alone = _worlds("cuda")
    cpu = _worlds("cpu")
    for index, (together, single, reference) in enumerate(
        zip(ensemble.worlds, alone, cpu, strict=True)
    ):
        single.step(8)
        reference.step(8)
        a = together.state()
        for world in (single, reference) if index < 2 else (single,):
            b = world.state()
            assert a.x.tobytes() == b.x.tobytes()
            assert a.vy.tobytes() == b.vy.tobytes()
            assert a.radius.tobytes() == b.radius.tobytes()
            assert a.objects.tobytes() == b.objects.tobytes()
        # The trio's middle particle adds its two neighbours' forces in another order than the
        # CPU: the same up to rounding.
        assert a.x == pytest.approx(reference.state().x, abs=1e-15)
        assert a.alive.tolist() == reference.state().alive.tolist()
    assert ensemble.steps == 8


def test_a_world_of_an_ensemble_is_stepped_only_through_it() -> None:
    ensemble = Ensemble(_worlds("cpu")[:2])
    with pytest.raises(RuntimeError, match="ensemble"):
        ensemble.worlds[0].step(1)


def _drift(world: World, steps: int) -> float:
    start = world.centroid(members_only=True)
    world.step(steps)
    end = world.centroid(members_only=True)
    return float(np.hypot(end[0] - start[0], end[1] - start[1]))


@pytest.mark.slow
def test_a_small_swarm_moves_as_far_on_the_gpu_as_on_the_cpu_over_seeds() -> None:
    # 12 particles in contact: each particle's pair sums add in the cell order on the GPU, in
    # the list order on the CPU, so the paths part in the last bits and then by chaos. Over
    # seeds the distance the centroid travels in a short cycle agrees within the CPU's spread.
    settings = PublishedSettings(rise_s=0.3, nx=1)  # a 0.6 s cycle: 60 steps
    steps = 120

    def world(seed: int, device: str) -> World:
        x, y = cluster(12, seed=seed)
        return World(x, y, controller=PublishedController(settings), lamp=Lamp(-3.0, 0.0),
                     seed=seed, device=device)  # fmt: skip

    cpu = np.array([_drift(world(seed, "cpu"), steps) for seed in range(16)])
    ensemble = Ensemble([world(seed, "cpu") for seed in range(4)])
    starts = [w.centroid(members_only=True) for w in ensemble.worlds]
    ensemble.step(steps)
    gpu = np.array([
        np.hypot(w.centroid(True)[0] - s[0], w.centroid(True)[1] - s[1])
        for w, s in zip(ensemble.worlds, starts, strict=True)
    ])  # fmt: skip
    assert cpu.mean() > 2e-4  # the swarm moved (the test means something)
    # The GPU's mean of 4 seeds within 4 standard errors of the CPU's mean over 16.
    assert abs(gpu.mean() - cpu.mean()) < 4 * cpu.std(ddof=1) / 2
    # Seed by seed the short run is the CPU's up to rounding carried by the dynamics.
    assert np.abs(gpu - cpu[:4]).max() < 0.5 * cpu.std(ddof=1)
