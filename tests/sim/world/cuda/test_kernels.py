"""The CUDA backend against the CPU world: the same bits where the arithmetic is the same (a lone
pair, contact, friction, walls, obstacles, passive objects, dead and free particles)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pytest

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Arena, DeadParticles, PassiveObject, Rect, ShadowMode, World
from particlebot.sim.world.light import Lamp
from tests.sim.world.conftest import R_MIN, Command, physics

FIELDS = ("x", "y", "vx", "vy", "radius", "alive", "member", "free", "acting", "objects")


def _pair(**kwargs: object) -> tuple[World, World]:
    """The same world on the CPU and on the GPU."""
    return World(**kwargs, device="cpu"), World(**kwargs, device="cuda")  # type: ignore[arg-type]


def _same_bits(cpu: World, gpu: World) -> None:
    a, b = cpu.state(), gpu.state()
    for name in FIELDS:
        left: npt.NDArray[np.generic] = getattr(a, name)
        right: npt.NDArray[np.generic] = getattr(b, name)
        assert left.tobytes() == right.tobytes(), f"{name}: {left} != {right}"


def test_a_lone_actuating_pair_in_magnet_range_takes_the_same_bits() -> None:
    cpu, gpu = _pair(x=[0.0, 2 * R_MIN + 0.005], y=[0.0, 0.01],
                     controller=PublishedController(), seed=3)  # fmt: skip
    start = cpu.state().x.copy()
    cpu.step(15)
    gpu.step(15)
    assert not np.array_equal(cpu.state().x, start)  # the magnets pulled them together
    _same_bits(cpu, gpu)


def test_two_overlapping_discs_are_pushed_apart_to_the_same_bits() -> None:
    params = physics(magnets=False)
    cpu, gpu = _pair(x=[0.0, 2 * R_MIN - 0.004], y=[0.0, 0.003], controller=Command(),
                     params=params)  # fmt: skip
    cpu.step(6)
    gpu.step(6)
    s = gpu.state()
    assert np.hypot(s.x[1] - s.x[0], s.y[1] - s.y[0]) > 2 * R_MIN - 0.004
    _same_bits(cpu, gpu)


def test_friction_holds_a_particle_the_magnets_pull_too_weakly() -> None:
    # At the magnets' reach a pull far below the static threshold: neither disc moves.
    gap = physics().magnet_cutoff * 0.95
    cpu, gpu = _pair(x=[0.0, 2 * R_MIN + gap], y=[0.0, 0.0], controller=Command(),
                     params=physics())  # fmt: skip
    cpu.step(5)
    gpu.step(5)
    s = gpu.state()
    assert s.x.tolist() == [0.0, 2 * R_MIN + gap]
    _same_bits(cpu, gpu)


def test_a_sliding_disc_stops_at_the_wall_and_an_obstacle_to_the_same_bits() -> None:
    params = physics(half_width=1.0)
    arena = Arena(rects=(Rect(0.3, 0.5, -0.5, 0.5),))
    cpu, gpu = _pair(x=[0.85, 0.05], y=[0.0, 0.0], velocity=([2.0, 1.5], [0.3, 0.0]),
                     controller=Command(R_MIN * 1.2), params=params, arena=arena)  # fmt: skip
    cpu.step(12)
    gpu.step(12)
    _same_bits(cpu, gpu)


def test_a_passive_object_pushed_by_a_disc_moves_to_the_same_bits() -> None:
    obj = PassiveObject(x=2 * R_MIN + 0.002, y=0.0, radius=R_MIN, mass_factor=1.0)
    cpu, gpu = _pair(x=[0.0], y=[0.0], velocity=([0.5], [0.0]), controller=Command(),
                     objects=[obj])  # fmt: skip
    cpu.step(8)
    gpu.step(8)
    assert gpu.state().objects[0, 2] > 0.0  # it was pushed along +x
    _same_bits(cpu, gpu)


def test_dead_free_and_shadowed_particles_match_the_cpu() -> None:
    # A line: two members, a free particle within the magnets' lock of the last (it joins),
    # one member dies at 0.05 s and detaches; a shadow holds what the wall hides from the lamp.
    gap = 0.5e-3
    x = [0.0, 2 * R_MIN + gap, 4 * R_MIN + 2 * gap, 0.0]
    y = [0.0, 0.0, 0.0, 0.6]
    cpu, gpu = _pair(x=x, y=y, free=[False, False, True, False], controller=PublishedController(),
                     dead=DeadParticles(1, 0.05, detach=True), seed=5, lamp=Lamp(-3.0, 0.6),
                     arena=Arena(rects=(Rect(-0.4, -0.3, 0.3, 0.9),)),
                     shadow=ShadowMode.STILL)  # fmt: skip
    cpu.step(10)
    gpu.step(10)
    s = gpu.state()
    assert s.member[2]  # the free one joined
    assert int((~s.alive).sum()) == 1
    _same_bits(cpu, gpu)


def test_a_world_stepped_in_pieces_and_read_between_matches_one_stepped_at_once() -> None:
    _, whole = _pair(x=[0.0, 2 * R_MIN + 0.004], y=[0.0, 0.0], controller=PublishedController())
    _, pieces = _pair(x=[0.0, 2 * R_MIN + 0.004], y=[0.0, 0.0], controller=PublishedController())
    whole.step(8)
    for _ in range(4):
        pieces.step(2)
        pieces.positions()  # a read copies the state back; stepping on must not disturb it
    assert whole.state().x.tobytes() == pieces.state().x.tobytes()


def test_a_gpu_snapshot_resumes_on_the_cpu_and_the_gpu_alike() -> None:
    _, gpu = _pair(x=[0.0, 2 * R_MIN + 0.004], y=[0.0, 0.0], controller=PublishedController())
    gpu.step(4)
    snap = gpu.snapshot()
    cpu_again = World.from_snapshot(snap, device="cpu")
    gpu_again = World.from_snapshot(snap, device="cuda")
    assert gpu_again.device == "cuda"
    cpu_again.step(4)
    gpu_again.step(4)
    _same_bits(cpu_again, gpu_again)


def test_the_stale_grid_is_refused_on_the_gpu() -> None:
    from particlebot.sim.world.cuda.device import DeviceError
    from particlebot.sim.world.params import NeighbourSearch, PhysicsParams

    params = PhysicsParams(neighbour_search=NeighbourSearch.PUBLISHED_STALE_GRID)
    with pytest.raises(DeviceError, match="stale grid"):
        World([0.0], [0.0], controller=Command(), params=params, device="cuda")


def test_the_firmware_controller_commands_through_the_host_to_the_same_bits() -> None:
    # The firmware controller has no GPU formula: its commands are uploaded step by step. Its
    # first wave starts at 3 s: the CPU gets there, then both backends go on from there.
    from particlebot.sim.particles.model.firmware import FirmwareController, FirmwareSettings

    controller = FirmwareController(FirmwareSettings(start_s=0.0, update_interval_s=20))
    x = [0.6, 0.6 + 2 * R_MIN + 0.5e-3]
    start = World(x, [0.0, 0.0], controller=controller, lamp=Lamp(0.0, 0.0), seed=2)
    start.step(295)
    cpu = World.from_snapshot(start.snapshot(), device="cpu")
    gpu = World.from_snapshot(start.snapshot(), device="cuda")  # (its own controller copy)
    cpu.step(25)
    gpu.step(25)
    assert (gpu.radii() > R_MIN).any()  # it actuated
    _same_bits(cpu, gpu)


@pytest.mark.parametrize("shape", ["blob", "line"])
def test_every_pair_within_reach_acts_once_in_a_grid_that_wraps(shape: str) -> None:
    # 60 particles: a squeezed blob over many cells, or a line of touching discs 10 m long that
    # wraps the swarm's 8 x 8 grid several times. One step: every particle's velocity (the sum
    # of all its pairs) equals the CPU's up to the order of the sums, none missing or doubled.
    from tests.sim.world.conftest import cluster

    rng = np.random.default_rng(4)
    if shape == "blob":
        x, y = cluster(60, seed=4, gap=-0.002)
    else:  # uneven overlaps and a zigzag, so that no particle's forces cancel
        x = np.cumsum(np.full(60, 2 * R_MIN) - rng.uniform(0.0, 0.004, 60)) - 4.5
        y = rng.uniform(-0.002, 0.002, 60)
    cpu, gpu = _pair(x=x, y=y, controller=PublishedController(), seed=1,
                     params=physics(friction=False))  # fmt: skip
    cpu.step(1)
    gpu.step(1)
    a, b = cpu.state(), gpu.state()
    assert np.abs(a.vx).max() > 0.0
    scale = np.abs(a.vx).max() + np.abs(a.vy).max()
    assert np.abs(a.vx - b.vx).max() < 1e-12 * scale
    assert np.abs(a.vy - b.vy).max() < 1e-12 * scale
