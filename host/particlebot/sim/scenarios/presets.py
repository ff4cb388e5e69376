"""The scenarios simulated radios name (virtual://N?scenario=line|blob|PATH): a line from the lamp,
an SI Algorithm-5 blob at a distance from it, or a scenario file."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from particlebot.sim.scenarios.scenario import (
    LampSpec,
    PlacementKind,
    Scenario,
    ScenarioError,
    SwarmSpec,
)

LINE_START_M = 0.10
"""A line's nearest particle: its centre this far along the floor from the lamp's foot."""
BLOB_START_M = 1.5
"""A blob's first particle (Algorithm 5 grows the blob around it): 1-2 m from the lamp, as the
paper's phototaxis experiments began."""
CONTRACTED_SPACING_M = 0.155
"""Neighbours of a line touch when contracted (2 R_min)."""
NAMES = ("line", "blob")


def line(
    count: int,
    *,
    start: float = LINE_START_M,
    spacing: float = CONTRACTED_SPACING_M,
    lamp: LampSpec | None = None,
    seed: int = 0,
) -> Scenario:
    """`count` particles in a line straight away from the lamp (along +x from its foot)."""
    lamp = lamp if lamp is not None else LampSpec()
    return Scenario(
        name="line",
        swarm=SwarmSpec(
            particles=count,
            placement=PlacementKind.LINE,
            at=(lamp.x + start, lamp.y),
            spacing=spacing,
            direction_deg=0.0,
        ),
        lamp=lamp,
        seed=seed,
    )


def blob(
    count: int, *, start: float = BLOB_START_M, lamp: LampSpec | None = None, seed: int = 0
) -> Scenario:
    """A random blob of `count` touching particles grown by SI Algorithm 5 around a first one
    `start` metres from the lamp's foot (along +x); the seed draws it."""
    lamp = lamp if lamp is not None else LampSpec()
    return Scenario(
        name="blob",
        swarm=SwarmSpec(
            particles=count, placement=PlacementKind.ALGORITHM5, at=(lamp.x + start, lamp.y)
        ),
        lamp=lamp,
        seed=seed,
    )


def read_file(path: Path) -> Scenario:
    """A scenario file: our TOML, or the published simulator's .cfg. ScenarioError (one line,
    file:line: key) when it cannot be read."""
    if not path.is_file():
        raise ScenarioError(f"{path}: no such scenario file")
    if path.suffix.lower() == ".toml":
        from particlebot.sim.scenarios.toml_file import read_scenario

        return read_scenario(path)
    from particlebot.sim.scenarios.published_cfg import read_published_cfg

    return read_published_cfg(path)


def with_particles(scenario: Scenario, count: int) -> Scenario:
    """The scenario with `count` robot particles (a placement from a file keeps its own)."""
    if scenario.swarm.placement is PlacementKind.FILE or count == scenario.swarm.particles:
        return scenario
    return replace(scenario, swarm=replace(scenario.swarm, particles=count))
