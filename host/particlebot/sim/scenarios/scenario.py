"""The Scenario: everything one run needs, as frozen data, whichever file it came from."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field, fields
from enum import StrEnum
from pathlib import Path
from typing import Literal

from particlebot.errors import ParticlebotError
from particlebot.machine import check_memory
from particlebot.options import LONGEST_S, PLACE, OptionError, check_number
from particlebot.sim.particles.model.firmware import FirmwareSettings
from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.world.arena import Circle, Rect
from particlebot.sim.world.light import ShadowMode
from particlebot.sim.world.params import (
    BYTES_FIXED,
    BYTES_PER_PARTICLE,
    STABLE,
    PhysicsParams,
)

Precision = Literal["float64", "float32"]

MAX_SEED = 2**63 - 1
"""TOML's whole numbers are 64-bit: a larger seed could not be written into a run folder."""
MAX_DURATION_S = LONGEST_S
MAX_STEPS = 10**10
"""Steps of one run: at the 10^6 steps a second a ten-particle swarm makes, three hours; a run
of more never finishes on any machine."""


class ScenarioError(ParticlebotError, ValueError):
    """A scenario that cannot run, said in one line: file, line, key, what is wrong."""


class PlacementKind(StrEnum):
    """How the swarm's particles are put down before the run."""

    ALGORITHM5 = "algorithm5"
    """SI Algorithm 5 as its text says: a random blob grown by tangent placements (our default)."""
    ALGORITHM5_PUBLISHED = "algorithm5-published"
    """Algorithm 5 as the published code runs it: coarse pivot steps and, in large swarms, discs
    put down a diameter out, so a sparser blob (placement.algorithm5_published)."""
    HEX = "hex"
    """A hexagonal blob, ring by ring around the first particle."""
    LINE = "line"
    """A straight line from the first particle."""
    FILE = "file"
    """Centres (and radii) listed in a CSV or TOML file."""


class ControllerKind(StrEnum):
    PUBLISHED = "published"
    """The published simulator's light wave."""
    FIRMWARE = "firmware"
    """What our firmware does (eq. 4, S_n by method A-D)."""


@dataclass(frozen=True)
class SwarmSpec:
    """The robot's particles and where they start."""

    particles: int = 10
    placement: PlacementKind = PlacementKind.ALGORITHM5
    at: tuple[float, float] = (0.0, 0.0)
    """The first particle's centre (m); the published simulator starts its swarm at (5, 0)."""
    spacing: float | None = None
    """Centre spacing of a line or hex blob (m); None: touching contracted particles."""
    direction_deg: float = 0.0
    """A line's direction, counterclockwise from +x."""
    file: Path | None = None
    """Positions for placement `file` (CSV x, y[, r] or TOML particles = [[x, y], ...])."""


@dataclass(frozen=True)
class LampSpec:
    """The point lamp (m); height None: the world's default (the SI's calibration height)."""

    x: float = 0.0
    y: float = 0.0
    height: float | None = None


@dataclass(frozen=True)
class ObjectSpec:
    """A passive disc the swarm may push. Position None: in front of the swarm, on the line from
    its centroid toward the lamp, one contracted radius clear of the nearest particle (as the
    published simulator puts its object in front of the swarm on the lamp's side)."""

    x: float | None = None
    y: float | None = None
    radius: float | None = None
    """Radius (m); None: radius_factor x the contracted particle radius."""
    radius_factor: float = 2.0
    mass_factor: float = 1.0
    friction_factor: float = 1.0
    attraction_factor: float = 0.0


@dataclass(frozen=True)
class DeadSpec:
    """Particles that stop actuating at `at_s` (chosen at random from the run's seed)."""

    count: int = 0
    fraction: float | None = None
    """Of the robot's particles, rounded; overrides count when given."""
    at_s: float = 0.0
    detach: bool = False
    """Dead particles let go of the robot (magnets off), as in Fig. S21."""

    def resolve(self, robot: int) -> int:
        return round(self.fraction * robot) if self.fraction is not None else self.count


@dataclass(frozen=True)
class FreeSpec:
    """Loose particles scattered at random in a rectangle, annexed when the robot touches them."""

    count: int = 0
    region: Rect | None = None


@dataclass(frozen=True)
class ControllerSpec:
    kind: ControllerKind = ControllerKind.PUBLISHED
    published: PublishedSettings = field(default_factory=PublishedSettings)
    firmware: FirmwareSettings = field(default_factory=FirmwareSettings)


@dataclass(frozen=True)
class OutputSpec:
    """What a run writes into its folder."""

    dump_interval_s: float = 60.0
    """A CSV row every so many simulated seconds (the published 60 s)."""
    per_particle: bool = False
    """Every particle's x, y, vx, vy, r in each row (the published `testing 1`)."""
    csv_name: str = "run.csv"
    snapshot_interval_s: float = 600.0
    """A snapshot to resume from every so many simulated seconds (and at the end or a stop)."""
    video_name: str = "run.mp4"
    """Name of the video `--video` writes."""
    video_frames: int = 200
    """About this many frames, evenly spread over the run (10 per second of video)."""


@dataclass(frozen=True)
class SourceMap:
    """Where a scenario came from: its file, the line of each key, and what the file calls a
    key where its name differs from the scenario's (the published format's nCells for
    swarm.particles), so that every error points at the file's own words."""

    path: Path | None = None
    lines: tuple[tuple[str, int], ...] = ()
    names: tuple[tuple[str, str], ...] = ()

    def where(self, key: str) -> str:
        """'file:line: key' as far as known, for the start of an error message."""
        found = dict(self.lines)
        shown = dict(self.names)
        # A key the file did not write out: point at its table.
        probe = key
        while probe not in found and "." in probe:
            probe = probe.rsplit(".", 1)[0]
        line = found.get(probe)
        name = shown.get(key)
        if name is None:
            name = shown.get(probe, key)
        place = "" if self.path is None else str(self.path)
        if line is not None:
            place += f":{line}"
        return f"{place}: {name}" if place else name

    def error(self, key: str, message: str) -> ScenarioError:
        return ScenarioError(f"{self.where(key)}: {message}")


@dataclass(frozen=True)
class Scenario:
    """Everything a run needs. Build a world from it with scenarios.build.build_world()."""

    name: str = "run"
    swarm: SwarmSpec = field(default_factory=SwarmSpec)
    lamp: LampSpec = field(default_factory=LampSpec)
    rects: tuple[Rect, ...] = ()
    circles: tuple[Circle, ...] = ()
    objects: tuple[ObjectSpec, ...] = ()
    dead: DeadSpec = field(default_factory=DeadSpec)
    free: FreeSpec = field(default_factory=FreeSpec)
    controller: ControllerSpec = field(default_factory=ControllerSpec)
    physics: PhysicsParams = field(default_factory=PhysicsParams)
    shadow: ShadowMode = ShadowMode.IGNORE
    duration_s: float = 600.0
    seed: int = 0
    precision: Precision = "float64"
    output: OutputSpec = field(default_factory=OutputSpec)
    source: SourceMap = field(default_factory=SourceMap, compare=False)

    def error(self, key: str, message: str) -> ScenarioError:
        """A one-line error about `key`, naming the file and line it came from."""
        return self.source.error(key, message)

    @property
    def steps(self) -> int:
        """Steps of the whole run."""
        return round(self.duration_s / self.physics.dt)

    def check_feasible(self) -> None:
        """ScenarioError when the run cannot finish (shorter than one step, more steps than
        MAX_STEPS); TooBigError when its world would not fit in this machine's memory. Called
        before anything is placed or allocated."""
        steps = self.duration_s / self.physics.dt
        if round(steps) < 1:
            raise self.error(
                "duration_s",
                f"{self.duration_s:g} s is less than one step of physics.dt = "
                f"{self.physics.dt:g} s: nothing would run",
            )
        if steps > MAX_STEPS:
            raise self.error(
                "duration_s",
                f"{self.duration_s:g} s in steps of {self.physics.dt:g} s is {steps:.3g} steps, "
                f"more than the {MAX_STEPS:.0e} a run can finish",
            )
        bodies = self.swarm.particles + self.free.count
        check_memory(BYTES_FIXED + BYTES_PER_PARTICLE * bodies, f"a swarm of {bodies:,} particles")
        if not 0 <= self.seed <= MAX_SEED:
            raise self.error("seed", f"must be a whole number 0..2^63 - 1, not {self.seed}")
        for key, value in self._places():
            try:
                check_number(value, PLACE)
            except OptionError as exc:
                raise self.error(key, f"{exc} (m)") from None

    def unusual(self) -> list[str]:
        """Warnings for values that can be right but seldom are (a run goes on with them)."""
        p = self.physics
        notes = []
        ringing = p.dt * math.sqrt(p.spring * max(1.0, p.obstacle_spring_factor))
        if ringing > STABLE / 2:
            notes.append(
                f"{self.source.where('physics.dt')}: dt x sqrt(spring) is {ringing:.2g}, near "
                f"the {STABLE:g} where contacts blow up: collisions will be coarse"
            )
        return notes

    def _places(self) -> Iterator[tuple[str, float]]:
        """Every coordinate and size of the scenario (m), by the key that gives it."""
        yield "lamp", self.lamp.x
        yield "lamp", self.lamp.y
        if self.lamp.height is not None:
            yield "lamp.height", self.lamp.height
        yield "swarm.at", self.swarm.at[0]
        yield "swarm.at", self.swarm.at[1]
        for i, rect in enumerate(self.rects, start=1):
            for value in (rect.x_min, rect.x_max, rect.y_min, rect.y_max):
                yield f"rectangle[{i}]", value
        for i, circle in enumerate(self.circles, start=1):
            for value in (circle.x, circle.y, circle.radius):
                yield f"circle[{i}]", value
        for i, thing in enumerate(self.objects, start=1):
            for maybe in (thing.x, thing.y, thing.radius):
                if maybe is not None:
                    yield f"object[{i}]", maybe

    @property
    def dump_every(self) -> int:
        """Steps between CSV rows."""
        return max(1, round(self.output.dump_interval_s / self.physics.dt))

    @property
    def snapshot_every(self) -> int:
        """Steps between periodic snapshots."""
        return max(1, round(self.output.snapshot_interval_s / self.physics.dt))


def physics_overrides(params: PhysicsParams) -> dict[str, float | bool]:
    """The fields of params that differ from the published defaults."""
    default = PhysicsParams()
    return {
        f.name: getattr(params, f.name)
        for f in fields(params)
        if getattr(params, f.name) != getattr(default, f.name)
    }


def finite(value: float) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
