"""The World as a whole: dead, detached and annexed particles, snapshots, precision, threads, the
numpy reference, the firmware controller in it, bad setups."""

from __future__ import annotations

import math
from pathlib import Path

import numba
import numpy as np
import pytest

from particlebot.protocol import Method
from particlebot.sim.particles.model.firmware import FirmwareController, FirmwareSettings
from particlebot.sim.particles.model.published import PublishedController, PublishedSettings
from particlebot.sim.world import (
    Arena,
    Circle,
    DeadParticles,
    Lamp,
    PassiveObject,
    PhysicsParams,
    Rect,
    ShadowMode,
    Snapshot,
    World,
)
from particlebot.sim.world import kernels as k
from particlebot.sim.world import world as world_module
from particlebot.sim.world.world import Precision
from tests.sim.world.conftest import R_MIN, Command, cluster, physics
from tests.sim.world.reference import lockstep


def _cycling(count: int, seed: int, **kwargs: object) -> World:
    x, y = cluster(count, seed)
    return World(x, y, controller=PublishedController(), lamp=Lamp(-4.0, 0.0), seed=seed,
                 **kwargs)  # type: ignore[arg-type]  # fmt: skip


def test_dead_particles_stop_at_their_time_chosen_by_the_seed() -> None:
    dead = DeadParticles(count=5, at_s=3.0)
    world = _cycling(20, seed=4, dead=dead)
    world.run(2.99)
    assert world.state().alive.all()
    world.run(0.02)
    state = world.state()
    assert np.count_nonzero(~state.alive) == 5
    assert not (state.acting & ~state.alive).any()
    frozen = state.radius[~state.alive]
    world.run(20.0)
    assert np.array_equal(world.radii()[~state.alive], frozen)  # they keep the radius they had
    assert (world.radii()[state.alive] != state.radius[state.alive]).any()  # the others move
    same = _cycling(20, seed=4, dead=dead)
    same.run(3.01)
    assert np.array_equal(same.state().alive, state.alive)


def test_a_detached_dead_particle_lets_go_and_leaves_the_robot() -> None:
    # 1.2 mm apart the magnets pull with ~6 N, more than static friction holds.
    x = np.array([0.0, 2 * R_MIN + 1.2e-3])
    held = World(x, np.zeros(2), controller=Command(), dead=DeadParticles(1, 0.0, detach=False))
    held.run(1.0)
    assert held.positions()[0][1] - held.positions()[0][0] < 2 * R_MIN + 0.9e-3
    loose = World(x, np.zeros(2), controller=Command(), dead=DeadParticles(1, 0.0, detach=True))
    loose.run(1.0)
    assert np.array_equal(loose.positions()[0], x)  # no magnet pulled either
    state = loose.state()
    assert np.count_nonzero(state.member) == 1 and np.count_nonzero(~state.alive) == 1


def test_a_free_particle_joins_the_robot_when_it_touches_it() -> None:
    x, y = cluster(6, seed=5)
    x = np.append(x, x.max() + 2 * R_MIN + 2.5e-3)  # 2.5 mm from the rightmost member
    y = np.append(y, y[np.argmax(x[:-1])])
    free = np.zeros(7, dtype=bool)
    free[-1] = True
    world = World(x, y, controller=PublishedController(), free=free, lamp=Lamp(5.0, 0.0))
    first = world.state()
    assert not first.member[-1] and first.free[-1] and not first.acting[-1]
    world.run(5.0)
    state = world.state()
    assert state.member[-1] and not state.free[-1] and state.acting[-1]


def test_shadowed_particles_read_no_light_go_last_or_hold_by_mode() -> None:
    wall = Arena(rects=(Rect(-1.0, -0.9, 0.5, 2.0),))
    x = np.array([0.0, 0.0])
    y = np.array([0.0, 1.0])  # the second one is behind the wall as seen from the lamp
    lamp = Lamp(-3.0, 1.0)
    settings = PublishedSettings(phase_noise=0.0)
    for mode in ShadowMode:
        controller = PublishedController(settings)
        world = World(x, y, controller=controller, arena=wall, lamp=lamp, shadow=mode)
        world.step(1)
        readings = world.view.light_readings()
        assert readings[0] > 0
        assert (readings[1] == 0) == (mode != ShadowMode.IGNORE)
        assert world.view.acting()[1] == (mode != ShadowMode.STILL)
        if mode == ShadowMode.LAST:
            assert controller.phases[1] == -(settings.nx - 1) * settings.rise_s


def test_a_run_resumed_from_a_saved_snapshot_equals_the_uninterrupted_run(tmp_path: Path) -> None:
    def build() -> World:
        x, y = cluster(30, seed=6)
        return World(
            x, y, controller=PublishedController(), lamp=Lamp(-4.0, 1.0), seed=6,
            arena=Arena(circles=(Circle(-1.0, 0.3, 0.2),)),
            objects=(PassiveObject(-0.6, -0.4, 0.15),),
            dead=DeadParticles(3, at_s=9.0, detach=True),
        )  # fmt: skip

    whole = build()
    whole.run(30.0)
    first = build()
    first.run(12.0)
    first.snapshot().save(tmp_path / "snap.npz")
    resumed = World.from_snapshot(Snapshot.load(tmp_path / "snap.npz"))
    resumed.run(18.0)
    a, b = whole.state(), resumed.state()
    for name in ("x", "y", "vx", "vy", "radius", "alive", "member", "objects"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert isinstance(resumed.controller, PublishedController)
    assert isinstance(whole.controller, PublishedController)
    assert np.array_equal(resumed.controller.phases, whole.controller.phases)
    assert resumed.t == whole.t


def test_a_snapshot_holding_a_steps_forces_resumes_as_one_without() -> None:
    # A step's force rows are zero between steps (the last pass clears them as it reads them,
    # and the pair passes add into them); snapshots written before that kept the last step's
    # forces there, and resuming one must not add them to the next step's.
    x, y = cluster(30, seed=8)
    world = World(x, y, controller=PublishedController(), lamp=Lamp(-4.0, 1.0), seed=8)
    world.run(6.0)
    snapshot = world.snapshot()
    assert not snapshot.arrays["body"][k.B_FX :].any()
    older = world.snapshot()  # (its own copies of the arrays)
    older.arrays["body"][k.B_FX :] = np.random.default_rng(8).normal(0.0, 5.0, (2, x.size))
    a, b = World.from_snapshot(snapshot), World.from_snapshot(older)
    a.run(3.0)
    b.run(3.0)
    assert np.array_equal(a.state().x, b.state().x) and np.array_equal(a.state().vy, b.state().vy)
    assert np.abs(a.state().vx).max() > 0  # (something moved)


@pytest.mark.slow
def test_a_large_swarm_resumes_bit_for_bit_between_re_orderings(tmp_path: Path) -> None:
    # A large swarm rebuilding its lists at every step re-orders its particles only at every
    # SORT_EVERY-th build (kernels.advance); a snapshot taken in between must resume exactly as
    # the uninterrupted run goes on. A tiny skin rebuilds at every step, as boiling does.
    count = world_module.PARALLEL_FROM + 100
    params = PhysicsParams(skin=1e-6)
    steps = 3 * k.SORT_EVERY + k.SORT_EVERY // 2
    whole = _cycling(count, seed=11, params=params)
    whole.step(2 * steps)
    first = _cycling(count, seed=11, params=params)
    first.step(steps)
    assert first._unsorted > 0  # between two re-orderings
    first.snapshot().save(tmp_path / "large.npz")
    resumed = World.from_snapshot(Snapshot.load(tmp_path / "large.npz"))
    resumed.step(steps)
    a, b = whole.state(), resumed.state()
    for name in ("x", "y", "vx", "vy", "radius"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert whole.rebuilds >= 2 * steps - 1 and np.abs(a.vx).max() > 0  # (not the first step)


def test_a_firmware_run_resumes_from_a_snapshot_too(tmp_path: Path) -> None:
    def build() -> World:
        x = 0.6 + np.arange(5) * (2 * R_MIN + 0.5e-3)
        controller = FirmwareController(FirmwareSettings(update_interval_s=20))
        return World(x, np.zeros(5), controller=controller, lamp=Lamp(0.0, 0.0), seed=2)

    whole = build()
    whole.run(50.0)
    first = build()
    first.run(25.0)
    first.snapshot().save(tmp_path / "firmware.npz")
    resumed = World.from_snapshot(Snapshot.load(tmp_path / "firmware.npz"))
    resumed.run(25.0)
    assert np.array_equal(whole.positions()[0], resumed.positions()[0])
    assert np.array_equal(whole.radii(), resumed.radii())


@pytest.mark.slow
def test_float32_and_float64_move_a_line_alike() -> None:
    advances = []
    precisions: tuple[Precision, ...] = ("float64", "float32")
    for precision in precisions:
        x = np.arange(5) * (2 * R_MIN + 0.5e-3)
        controller = PublishedController(PublishedSettings(phase_noise=0.0))
        world = World(x, np.zeros(5), controller=controller, lamp=Lamp(-3.0, 0.0), seed=1,
                      precision=precision)  # fmt: skip
        start = world.light_distance()
        world.run(120.0)
        advances.append(start - world.light_distance())
    assert advances[0] > 0.1  # about 0.3 m
    assert advances[1] == pytest.approx(advances[0], rel=0.1)


def test_results_do_not_depend_on_the_number_of_threads() -> None:
    # Enough particles for parallel chunks; pairs of a chunk reach only the next chunk.
    count = world_module.PARALLEL_FROM + 100
    ends = []
    for threads in (1, 2):
        previous = numba.get_num_threads()
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]
        try:
            world = _cycling(count, seed=7, params=physics(friction=False))
            world.run(1.0)
            ends.append(world.state())
        finally:
            numba.set_num_threads(previous)
    assert np.array_equal(ends[0].x, ends[1].x) and np.array_equal(ends[0].vy, ends[1].vy)
    # Newton's third law across chunk boundaries: pair forces cancel exactly (i gets f, j gets
    # -f), so the sum of ~2,000 velocities of ~1e-2 m/s is rounding alone, about N eps |v| per
    # step (1e-14 m/s), 1e-12 over 100 steps; a force applied to one side only is ~1e-3 m/s.
    assert abs(ends[0].vx.sum()) < 1e-9


def test_kernels_follow_a_plain_numpy_transcription_of_the_published_step() -> None:
    x, y = cluster(10, seed=8)
    controller = PublishedController()
    world = World(x, y, controller=controller, lamp=Lamp(-4.0, 0.5), seed=8)
    worst, reference = lockstep(world, controller, steps=600)
    # Tolerance: the kernels contract a*b+c into fused multiply-adds where the CPU has them and
    # re-associate sums (fastmath contract/reassoc), numpy does neither: each step differs by a
    # few ulps of a position (1e-16 m scale), and a 10-particle cluster's contacts do not amplify
    # that in 600 steps (4e-16 m apart at the end on an AVX2 CPU). 1e-9 m catches a wrong law or
    # a missed pair (either moves a particle by micrometres within a few steps) on any CPU.
    assert np.abs(world.radii() - reference.r).max() < 1e-9
    assert worst < 1e-9
    assert np.abs(world.state().vx).max() > 0  # and something happened


@pytest.mark.parametrize("method", [Method.DIRECT, Method.COUNTING])
def test_the_firmware_controller_moves_a_line_toward_the_lamp(method: Method) -> None:
    x = 0.6 + np.arange(5) * (2 * R_MIN + 0.5e-3)
    controller = FirmwareController(FirmwareSettings(method=method, update_interval_s=60))
    world = World(x, np.zeros(5), controller=controller, lamp=Lamp(0.0, 0.0), seed=1)
    start = world.light_distance()
    world.run(180.0)
    assert start - world.light_distance() > 0.1  # ~0.25 m in 3 minutes
    assert controller.round >= 2


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"arena": Arena(circles=(Circle(0.1, 0.0, 0.05),))}, "cut into an obstacle"),
        ({"dead": DeadParticles(3)}, "dead particles of a robot of 2"),
        ({"radius": [0.05, 0.08]}, "radii must lie in"),
        ({"params": PhysicsParams(half_width=0.2)}, "inside the walls"),
        (
            {
                "objects": (PassiveObject(0.0, 0.0, 0.1),),
                "arena": Arena(circles=(Circle(0.0, 0.1, 0.05),)),
            },
            "cut into an obstacle",
        ),
    ],
)
def test_bad_setups_are_refused_with_one_line(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        World([0.0, 0.3], [0.0, 0.0], controller=Command(), **kwargs)  # type: ignore[arg-type]


def test_non_finite_positions_are_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        World([0.0, math.nan], [0.0, 0.0], controller=Command())
