"""Building worlds from scenarios: placement from the seed, objects in front of the swarm, loose
particles in their region, walls that grow to hold a swarm, obstacles that refuse a swarm."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from particlebot.sim.particles.model.firmware import FirmwareController
from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.build import build_world, place_swarm
from particlebot.sim.scenarios.scenario import (
    ControllerKind,
    ControllerSpec,
    DeadSpec,
    FreeSpec,
    LampSpec,
    ObjectSpec,
    PlacementKind,
    Scenario,
    ScenarioError,
    SwarmSpec,
)
from particlebot.sim.scenarios.toml_file import parse_scenario
from particlebot.sim.world.arena import Circle, Rect
from particlebot.sim.world.params import PhysicsParams

R = PhysicsParams().r_min


def small(**changes: object) -> Scenario:
    base = Scenario(swarm=SwarmSpec(particles=20), lamp=LampSpec(-3.0, 0.0), duration_s=1.0)
    return replace(base, **changes)  # type: ignore[arg-type]


def test_the_swarm_is_placed_by_algorithm5_from_the_seed() -> None:
    first = place_swarm(small(seed=4)).xy
    again = place_swarm(small(seed=4)).xy
    other = place_swarm(small(seed=5)).xy

    np.testing.assert_array_equal(first, again)
    assert not np.allclose(first, other)
    assert tuple(first[0]) == (0.0, 0.0)


def test_the_world_holds_the_placed_swarm_and_the_scenarios_controller() -> None:
    built = build_world(small(seed=2))

    x, y = built.world.positions()
    np.testing.assert_array_equal(np.column_stack((x, y)), place_swarm(small(seed=2)).xy)
    assert built.particles == 20 and built.notes == []
    assert isinstance(built.world.controller, PublishedController)
    firmware = small(controller=ControllerSpec(kind=ControllerKind.FIRMWARE))
    assert isinstance(build_world(firmware).world.controller, FirmwareController)


def test_an_object_without_a_position_starts_in_front_of_the_swarm_toward_the_lamp() -> None:
    built = build_world(small(objects=(ObjectSpec(radius_factor=2.0),)))

    (obj,) = built.world.objects
    x, y = built.world.positions()
    centre = np.array([x.mean(), y.mean()])
    toward = np.array([-3.0, 0.0]) - centre
    offset = np.array([obj.x, obj.y]) - centre
    # On the line to the lamp, ahead of every particle, one contracted radius clear of them.
    assert abs(offset[0] * toward[1] - offset[1] * toward[0]) < 1e-9 * np.hypot(*toward) ** 2
    assert obj.radius == pytest.approx(2 * R)
    unit = toward / np.hypot(*toward)
    ahead = (np.column_stack((x, y)) - centre) @ unit + R
    assert offset @ unit - obj.radius - ahead.max() == pytest.approx(R, abs=1e-9)
    assert (np.hypot(x - obj.x, y - obj.y) - R - obj.radius >= R - 1e-9).all()


def test_loose_particles_lie_in_their_region_clear_of_everything() -> None:
    region = Rect(-2.5, -1.5, -0.5, 0.5)
    scenario = small(free=FreeSpec(12, region), circles=(Circle(-2.0, 0.0, 0.2),))

    built = build_world(scenario)

    state = built.world.state()
    assert built.world.count == 32 and int(state.free.sum()) == 12
    loose = np.column_stack((state.x[state.free], state.y[state.free]))
    assert (loose[:, 0] >= region.x_min + R).all() and (loose[:, 0] <= region.x_max - R).all()
    assert (loose[:, 1] >= region.y_min + R).all() and (loose[:, 1] <= region.y_max - R).all()
    assert (np.hypot(loose[:, 0] + 2.0, loose[:, 1]) >= 0.2 + R).all()
    everyone = np.column_stack((state.x, state.y))
    assert not cKDTree(everyone).query_pairs(2 * R - 1e-9)


def test_too_many_loose_particles_for_their_region_say_so() -> None:
    scenario = small(free=FreeSpec(50, Rect(-2.0, -1.6, -0.2, 0.2)))

    with pytest.raises(ScenarioError, match="loose particles fit"):
        build_world(scenario)


def test_walls_move_out_for_a_swarm_beyond_the_published_world() -> None:
    scenario = small(swarm=SwarmSpec(particles=3, placement=PlacementKind.LINE, at=(70.0, 0.0)))

    built = build_world(scenario)

    assert built.world.params.half_width >= 70.0 + 2 * 2 * R + R
    assert built.scenario.physics.half_width == built.world.params.half_width
    assert "walls moved out" in built.notes[0]


def test_walls_a_scenario_set_itself_do_not_move(tmp_path: Path) -> None:
    text = (
        "[swarm]\nplacement = 'line'\nparticles = 3\nat = [70.0, 0.0]\n[physics]\nhalf_width = 50\n"
    )
    scenario = parse_scenario(text, tmp_path / "walls.toml")

    with pytest.raises(ScenarioError, match=r"walls.toml:6: physics.half_width: the swarm reaches"):
        build_world(scenario)


def test_a_swarm_on_an_obstacle_names_the_obstacles_line(tmp_path: Path) -> None:
    text = (
        "[swarm]\nparticles = 10\n"
        "[[rectangle]]\nx = [5, 6]\ny = [5, 6]\n"
        "[[rectangle]]\nx = [0.1, 0.3]\ny = [-1, 1]\n"
    )
    scenario = parse_scenario(text, tmp_path / "blocked.toml")

    with pytest.raises(ScenarioError) as caught:
        build_world(scenario)

    assert str(caught.value).startswith(f"{tmp_path / 'blocked.toml'}:6: rectangle[2]: ")
    assert "cut into this obstacle" in str(caught.value)


def test_an_object_on_the_swarm_names_the_objects_line(tmp_path: Path) -> None:
    text = "[swarm]\nparticles = 10\n\n[[object]]\nx = 0.1\ny = 0.0\n"
    scenario = parse_scenario(text, tmp_path / "on.toml")

    with pytest.raises(ScenarioError, match=r"on.toml:4: object\[1\]: the object overlaps"):
        build_world(scenario)


def test_overlapping_positions_from_a_file_are_refused(tmp_path: Path) -> None:
    (tmp_path / "swarm.csv").write_text("0, 0\n0.1, 0\n")
    text = "[swarm]\nplacement = 'file'\nfile = 'swarm.csv'\n"
    scenario = parse_scenario(text, tmp_path / "f.toml")

    with pytest.raises(ScenarioError, match=r"f.toml:3: swarm.file: particles 0 and 1 overlap"):
        build_world(scenario)


def test_a_line_closer_than_touching_is_refused() -> None:
    swarm = SwarmSpec(particles=3, placement=PlacementKind.LINE, spacing=0.1)

    with pytest.raises(ScenarioError, match=r"swarm\.spacing: particles 0 and 1 overlap"):
        build_world(small(swarm=swarm))


def test_a_dead_fraction_becomes_a_count_of_the_robot() -> None:
    built = build_world(small(dead=DeadSpec(fraction=0.25, at_s=0.0)))

    built.world.step(1)
    assert int((~built.world.state().alive).sum()) == 5


def test_radii_from_a_file_start_the_particles_part_expanded(tmp_path: Path) -> None:
    (tmp_path / "swarm.csv").write_text("x, y, r\n0, 0, 0.1\n0.3, 0, 0.0775\n")
    text = "[swarm]\nplacement = 'file'\nfile = 'swarm.csv'\n"

    built = build_world(parse_scenario(text, tmp_path / "f.toml"))

    np.testing.assert_allclose(built.world.radii(), [0.1, 0.0775])
    assert math.isclose(built.world.params.r_min, R)
