"""From a Scenario to a running World: the swarm placed, objects and loose particles put down,
everything checked against the obstacles, the controller chosen."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from particlebot.sim.particles.model.controller import Controller
from particlebot.sim.particles.model.firmware import FirmwareController
from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import (
    Placement,
    PlacementError,
    algorithm5,
    algorithm5_published,
    from_file,
    hexagonal,
    line,
    overlaps,
    scatter,
)
from particlebot.sim.scenarios.scenario import (
    ControllerKind,
    ObjectSpec,
    PlacementKind,
    Scenario,
)
from particlebot.sim.world.arena import Arena
from particlebot.sim.world.bodies import DeadParticles, PassiveObject
from particlebot.sim.world.cuda.device import DeviceError
from particlebot.sim.world.light import Lamp
from particlebot.sim.world.params import PhysicsParams
from particlebot.sim.world.world import World

FloatArray = npt.NDArray[np.float64]

PLACEMENT_STREAM = 0x5EED_0005
"""Spawn key of the placement's random stream: apart from the streams the World spawns from the
same seed (its own and its controller's), so that placing never shares draws with running."""
WALL_MARGIN_M = 1.0
"""Room left between the farthest body and the walls when they are moved out to hold a swarm."""


@dataclass
class Built:
    """A world ready to step, and what building it found worth saying."""

    world: World
    scenario: Scenario
    """The scenario as run (walls moved out if they had to be)."""
    particles: int
    """The robot's particles: indices 0..particles-1; loose (free) ones follow."""
    notes: list[str] = field(default_factory=list)


def controller_for(scenario: Scenario) -> Controller:
    spec = scenario.controller
    if spec.kind is ControllerKind.FIRMWARE:
        return FirmwareController(spec.firmware)
    return PublishedController(spec.published)


def place_swarm(scenario: Scenario) -> Placement:
    """The robot's particles as the scenario places them (reproducible from its seed)."""
    swarm, params = scenario.swarm, scenario.physics
    rng = np.random.default_rng(
        np.random.SeedSequence(scenario.seed, spawn_key=(PLACEMENT_STREAM,))
    )
    spacing = swarm.spacing if swarm.spacing is not None else 2 * params.r_min
    try:
        if swarm.placement is PlacementKind.FILE:
            assert swarm.file is not None
            placement = from_file(swarm.file)
        elif swarm.placement is PlacementKind.HEX:
            placement = hexagonal(swarm.particles, spacing, swarm.at)
        elif swarm.placement is PlacementKind.LINE:
            placement = line(swarm.particles, spacing, swarm.direction_deg, swarm.at)
        elif swarm.placement is PlacementKind.ALGORITHM5_PUBLISHED:
            placement = algorithm5_published(swarm.particles, params.r_min, rng, swarm.at)
        else:
            placement = algorithm5(swarm.particles, params.r_min, rng, swarm.at)
    except PlacementError as exc:
        raise scenario.error("swarm.file" if swarm.file else "swarm", str(exc)) from None
    radii = (
        placement.radii if placement.radii is not None else np.full(placement.count, params.r_min)
    )
    if placement.radii is not None:
        bad = (radii < params.r_min) | (radii > params.r_max)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise scenario.error(
                "swarm.file",
                f"particle {i} has radius {radii[i]:g} m, outside "
                f"{params.r_min:g}..{params.r_max:g}",
            )
    pair = overlaps(placement.xy, radii)
    if pair is not None:
        key = "swarm.file" if swarm.placement is PlacementKind.FILE else "swarm.spacing"
        i, j = pair
        raise scenario.error(key, f"particles {i} and {j} overlap")
    return placement


def build_world(
    scenario: Scenario, controller: Controller | None = None, device: str = "cpu"
) -> Built:
    """The World a scenario describes, with its controller bound (`controller`, when given,
    instead of the scenario's: the swarm of firmware particles drives the world with theirs),
    on `device` (World's; DeviceError, a ValueError too, when it cannot be had);
    ScenarioError (one line that names the file, line and key) when the scenario cannot be put
    down as written; TooBigError when it would not fit in memory."""
    scenario.check_feasible()
    params = scenario.physics
    placement = place_swarm(scenario)
    xy = placement.xy
    radii = placement.radii if placement.radii is not None else np.full(len(xy), params.r_min)
    arena = Arena(rects=scenario.rects, circles=scenario.circles)
    _check_obstacles(scenario, arena, xy, radii, "the swarm's particles", "swarm")

    objects = _objects(scenario, xy, radii)
    for m, o in enumerate(objects):
        where = f"object[{m + 1}]"
        _check_obstacles(
            scenario, arena, np.array([[o.x, o.y]]), np.array([o.radius]), "the object", where
        )

    free_mask = np.zeros(len(xy), dtype=np.bool_)
    if scenario.free.count > 0:
        assert scenario.free.region is not None
        region = scenario.free.region
        bodies_xy = np.concatenate([xy, np.array([[o.x, o.y] for o in objects]).reshape(-1, 2)])
        bodies_r = np.concatenate([radii, np.array([o.radius for o in objects])])
        try:
            loose = scatter(
                scenario.free.count,
                params.r_min,
                (region.x_min, region.x_max, region.y_min, region.y_max),
                np.random.default_rng(
                    np.random.SeedSequence(scenario.seed, spawn_key=(PLACEMENT_STREAM, 1))
                ),
                bodies_xy,
                bodies_r,
                _blocker(arena),
            )
        except PlacementError as exc:
            raise scenario.error("free", str(exc)) from None
        xy = np.concatenate([xy, loose.xy])
        radii = np.concatenate([radii, np.full(loose.count, params.r_min)])
        free_mask = np.concatenate([free_mask, np.ones(loose.count, dtype=np.bool_)])

    scenario, notes = _walls(scenario, xy, radii, objects)
    notes = scenario.unusual() + notes
    robot = placement.count
    dead = scenario.dead.resolve(robot)
    if dead > robot:
        raise scenario.error("dead", f"{dead} dead particles of a robot of {robot}")
    lamp = Lamp(scenario.lamp.x, scenario.lamp.y)
    if scenario.lamp.height is not None:
        lamp = replace(lamp, height=scenario.lamp.height)
    try:
        world = World(
            xy[:, 0],
            xy[:, 1],
            controller=controller if controller is not None else controller_for(scenario),
            params=scenario.physics,
            arena=arena,
            lamp=lamp,
            shadow=scenario.shadow,
            objects=objects,
            free=free_mask,
            dead=DeadParticles(dead, scenario.dead.at_s, scenario.dead.detach),
            radius=radii,
            seed=scenario.seed,
            precision=scenario.precision,
            device=device,
        )
    except DeviceError:
        raise
    except ValueError as exc:
        raise scenario.error("swarm", f"the world refuses this scenario: {exc}") from None
    return Built(world, scenario, robot, notes)


def _blocker(arena: Arena) -> Callable[[FloatArray, FloatArray], npt.NDArray[np.bool_]]:
    def blocked(xy: FloatArray, r: FloatArray) -> npt.NDArray[np.bool_]:
        return arena.overlapping(xy[:, 0], xy[:, 1], r)

    return blocked


def _check_obstacles(
    scenario: Scenario, arena: Arena, xy: FloatArray, radii: FloatArray, what: str, key: str
) -> None:
    """Names the first obstacle that discs cut into (its line in the file)."""
    x, y = xy[:, 0], xy[:, 1]
    single = [(f"rectangle[{i}]", Arena(rects=(r,))) for i, r in enumerate(arena.rects, 1)]
    single += [(f"circle[{i}]", Arena(circles=(c,))) for i, c in enumerate(arena.circles, 1)]
    for obstacle, alone in single:
        hit = alone.overlapping(x, y, radii)
        if hit.any():
            first = int(np.flatnonzero(hit)[0])
            at = f"at {x[first]:.3f}, {y[first]:.3f}"
            which = f"{int(hit.sum())} of them, particle {first} {at}" if len(x) > 1 else at
            raise scenario.error(
                obstacle, f"{what} cut into this obstacle ({which}); move it or the {key}"
            )


def _objects(scenario: Scenario, xy: FloatArray, radii: FloatArray) -> tuple[PassiveObject, ...]:
    params = scenario.physics
    placed: list[PassiveObject] = []
    for m, spec in enumerate(scenario.objects):
        key = f"object[{m + 1}]"
        radius = spec.radius if spec.radius is not None else spec.radius_factor * params.r_min
        x, y = (
            (spec.x, spec.y)
            if spec.x is not None and spec.y is not None
            else _in_front(scenario, spec, xy, radii, radius)
        )
        gaps = np.hypot(xy[:, 0] - x, xy[:, 1] - y) - radii - radius
        if (gaps < 0).any():
            i = int(np.argmin(gaps))
            raise scenario.error(
                key, f"the object overlaps particle {i} of the swarm by {-gaps[i] * 1000:.1f} mm"
            )
        for n, other in enumerate(placed, start=1):
            if math.hypot(other.x - x, other.y - y) < other.radius + radius:
                raise scenario.error(key, f"the object overlaps object {n}")
        try:
            placed.append(
                PassiveObject(
                    x, y, radius, spec.mass_factor, spec.friction_factor, spec.attraction_factor
                )
            )
        except ValueError as exc:
            raise scenario.error(key, str(exc)) from None
    return tuple(placed)


def _in_front(
    scenario: Scenario, spec: ObjectSpec, xy: FloatArray, radii: FloatArray, radius: float
) -> tuple[float, float]:
    """On the line from the swarm's centroid to the lamp, one contracted radius clear of the
    particle that reaches farthest that way (the published simulator: left of the leftmost
    particle, its lamp lying to the left)."""
    centre = xy.mean(axis=0)
    toward = np.array([scenario.lamp.x, scenario.lamp.y]) - centre
    length = float(np.hypot(*toward))
    direction = toward / length if length > 0 else np.array([-1.0, 0.0])
    reach = float(((xy - centre) @ direction + radii).max())
    distance = reach + scenario.physics.r_min + radius
    return float(centre[0] + distance * direction[0]), float(centre[1] + distance * direction[1])


def _walls(
    scenario: Scenario, xy: FloatArray, radii: FloatArray, objects: tuple[PassiveObject, ...]
) -> tuple[Scenario, list[str]]:
    """Moves the walls out when a swarm outgrows the published +-64 m (a million particles of
    Algorithm 5 span ~180 m), unless the scenario set them itself."""
    params = scenario.physics
    extent = float(np.max(np.abs(xy) + radii[:, None]))
    for o in objects:
        extent = max(extent, abs(o.x) + o.radius, abs(o.y) + o.radius)
    if extent <= params.half_width:
        return scenario, []
    if params.half_width != PhysicsParams().half_width:
        raise scenario.error(
            "physics.half_width",
            f"the swarm reaches {extent:.1f} m from the origin, beyond the walls at "
            f"+-{params.half_width:g} m",
        )
    half_width = float(math.ceil(extent + WALL_MARGIN_M))
    note = (
        f"walls moved out from +-{params.half_width:g} m to +-{half_width:g} m to hold the "
        "swarm (physics.half_width)"
    )
    return replace(scenario, physics=replace(params, half_width=half_width)), [note]
