"""The one place the studies touch the simulator: a run's setup in, its outcome out.

A study describes each run as a WorldSetup in the *study frame* (metres, origin at the swarm's
initial centroid after placement, so that "2.5 DPD from the initial centroid" is a number). The
simulator's scenarios put the swarm where its placement puts it (Algorithm 5 grows from the
origin), so this module places the swarm first, then moves the lamp, obstacles, object and
free-particle region by the placement's centroid: the simulator's frame is the study frame
shifted by that centroid, and every position that comes back is shifted back.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from particlebot.errors import ParticlebotError
from particlebot.sim.particles.model.published import PublishedSettings
from particlebot.sim.runs.run import SCENARIO_FILE, Run, Summary, latest_snapshot
from particlebot.sim.runs.simcsv import read_published_csv
from particlebot.sim.scenarios.build import build_world, place_swarm
from particlebot.sim.scenarios.scenario import (
    ControllerKind,
    ControllerSpec,
    DeadSpec,
    FreeSpec,
    LampSpec,
    ObjectSpec,
    OutputSpec,
    PlacementKind,
    Scenario,
    ScenarioError,
    SwarmSpec,
)
from particlebot.sim.world.arena import Arena, Circle, Rect
from particlebot.sim.world.light import ShadowMode
from particlebot.sim.world.params import PhysicsParams
from particlebot.studies.spec import PassiveObject as StudyObject
from particlebot.studies.spec import Rect as StudyRect
from particlebot.studies.spec import RunSpec, ShareDone, SimOutcome, Track, WorldSetup

PLACEMENT_KINDS = {
    "blob": PlacementKind.ALGORITHM5,
    "published-blob": PlacementKind.ALGORITHM5_PUBLISHED,
    "hex": PlacementKind.HEX,
    "line": PlacementKind.LINE,
}
SHADOW_MODES = {"ignore": ShadowMode.IGNORE, "last": ShadowMode.LAST, "still": ShadowMode.STILL}
CONTROLLER_KINDS = {"published": ControllerKind.PUBLISHED, "firmware": ControllerKind.FIRMWARE}
TURN_STEP_DEG = 15.0
"""A placement that cuts into an obstacle or the object is turned about its centroid in steps of
this many degrees until it clears (Algorithm 5's blobs have no preferred direction, so turning
one keeps it a sample of the same placements; a 10-particle blob reaches 0.91 DPD at worst, past
the gap study's wall and the carry study's object at 0.75 DPD)."""
POSITIONS_FILE = "turned-placement.csv"


class SetupError(ParticlebotError, ValueError):
    """A setup the simulator cannot put down (one line: what is in the way)."""


@dataclass(frozen=True)
class Framed:
    """A setup as the simulator's scenario, and how the two frames relate."""

    scenario: Scenario
    offset: tuple[float, float]
    """The placement's centroid in the simulator's frame: simulator = study + offset."""
    turned_deg: float
    """How far the placement was turned to clear the obstacles (0 almost always)."""
    positions: np.ndarray | None
    """The turned placement's centres (simulator frame), when it was turned."""


def warm_up() -> None:
    """Compiles (or loads from numba's on-disk cache) every kernel a study uses in this process,
    so that a worker's first run does not also pay for compilation: a tiny run with each feature
    of the studies' worlds (a wall, a shadow, a passive object, dead particles that detach, free
    particles), a few seconds simulated."""
    setup = WorldSetup(
        particles=5,
        seed=1,
        duration_s=1.5,
        lamp_x=3.0,
        rects=(StudyRect(1.0, 1.155, 0.3, 2.0), StudyRect(1.0, 1.155, -2.0, -0.3)),
        passive_object=StudyObject(x=-0.8, y=0.0, radius_factor=1.0),
        dead=1,
        dead_at_s=0.5,
        detach_dead=True,
        free_particles=2,
        free_region=StudyRect(0.4, 0.9, -0.5, 0.5),
        shadow="last",
        noise_diameters=0.5,
        dump_interval_s=0.5,
    )
    simulate(setup)


def frame(setup: WorldSetup) -> Framed:
    """The simulator's scenario for a setup (see the module's description); SetupError when the
    setup asks for something the simulator has not got."""
    try:
        placement_kind = PLACEMENT_KINDS[setup.placement]
        shadow = SHADOW_MODES[setup.shadow]
        controller = CONTROLLER_KINDS[setup.controller]
    except KeyError as exc:
        raise SetupError(f"the simulator has no {exc.args[0]!r} here") from None
    physics, published = _overridden(setup)
    base = Scenario(
        name="study",
        swarm=SwarmSpec(particles=setup.particles, placement=placement_kind),
        seed=setup.seed,
        duration_s=setup.duration_s,
        shadow=shadow,
        physics=physics,
        controller=ControllerSpec(kind=controller, published=published),
        dead=DeadSpec(count=setup.dead, at_s=setup.dead_at_s, detach=setup.detach_dead),
        output=OutputSpec(dump_interval_s=track_interval_s(setup), per_particle=setup.per_particle),
    )
    placement = place_swarm(base)
    xy = placement.xy
    cx, cy = (float(v) for v in xy.mean(axis=0))
    lamp = LampSpec(setup.lamp_x + cx, setup.lamp_y + cy, setup.lamp_height)
    rects = tuple(_rect(r, cx, cy) for r in setup.rects)
    circles = tuple(Circle(c.x + cx, c.y + cy, c.radius) for c in setup.circles)
    objects: tuple[ObjectSpec, ...] = ()
    if (o := setup.passive_object) is not None:
        objects = (
            ObjectSpec(
                x=o.x + cx,
                y=o.y + cy,
                radius_factor=o.radius_factor,
                mass_factor=o.mass_factor,
                friction_factor=o.friction_factor,
                attraction_factor=o.attraction_factor,
            ),
        )
    free = FreeSpec()
    if setup.free_particles > 0:
        if setup.free_region is None:
            raise SetupError(f"{setup.free_particles} free particles need a free_region")
        free = FreeSpec(setup.free_particles, _rect(setup.free_region, cx, cy))
    scenario = replace(base, lamp=lamp, rects=rects, circles=circles, objects=objects, free=free)
    turned, positions = _clear(scenario, xy - (cx, cy), (cx, cy))
    return Framed(scenario, (cx, cy), turned, positions)


def _overridden(setup: WorldSetup) -> tuple[PhysicsParams, PublishedSettings]:
    """The world's numbers and the published controller's, with the setup's overrides."""
    physics_fields = {f.name: f for f in fields(PhysicsParams)}
    physics: dict[str, Any] = {}
    controller: dict[str, Any] = {"noise_diameters": setup.noise_diameters}
    for name, value in setup.overrides:
        if name in physics_fields:
            kind = physics_fields[name].type
            physics[name] = bool(value) if kind in (bool, "bool") else value
        elif name == "update_cycles":
            controller[name] = round(value)
        else:
            controller[name] = value
    try:
        return PhysicsParams(**physics), PublishedSettings(**controller)
    except (TypeError, ValueError) as exc:
        raise SetupError(f"overrides {setup.overrides}: {exc}") from None


def _rect(r: StudyRect, dx: float, dy: float) -> Rect:
    return Rect(r.x_min + dx, r.x_max + dx, r.y_min + dy, r.y_max + dy)


def _clear(
    scenario: Scenario, relative: np.ndarray, centre: tuple[float, float]
) -> tuple[float, np.ndarray | None]:
    """The smallest turn (0, +-15, +-30 ... degrees) of the placement about its centroid that
    keeps every particle out of the obstacles and the passive objects, and the turned centres
    (None when no turn was needed)."""
    r = scenario.physics.r_min
    arena = Arena(rects=scenario.rects, circles=scenario.circles)
    discs = [
        (o.x, o.y, o.radius if o.radius is not None else o.radius_factor * r)
        for o in scenario.objects
        if o.x is not None and o.y is not None
    ]
    steps = round(180.0 / TURN_STEP_DEG)
    for k in range(2 * steps):
        angle = TURN_STEP_DEG * ((k + 1) // 2) * (1 if k % 2 else -1) if k else 0.0
        c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
        xy = relative @ np.array([[c, s], [-s, c]]) + centre
        radii = np.full(len(xy), r)
        if arena.overlapping(xy[:, 0], xy[:, 1], radii).any():
            continue
        if any((np.hypot(xy[:, 0] - x, xy[:, 1] - y) < r + radius).any() for x, y, radius in discs):
            continue
        return angle, (None if k == 0 else xy)
    raise SetupError(
        f"the swarm of {len(relative)} particles (seed {scenario.seed}) cuts into an obstacle or "
        "the object however it is turned; move them further out"
    )


def track_interval_s(setup: WorldSetup) -> float:
    """The centroid track's interval: setup.dump_interval_s, or a little less where that does not
    divide the duration, so that the track ends at the run's end."""
    rows = math.ceil(setup.duration_s / setup.dump_interval_s - 1e-9)
    return setup.duration_s / max(1, rows)


def run_one(
    spec: RunSpec,
    run_dir: Path | None = None,
    progress: ShareDone | None = None,
    device: str = "cpu",
) -> SimOutcome:
    """Simulates spec.setup and returns what the study's measure needs, in the study frame.

    run_dir: where the run keeps its folder (the published CSV, npz snapshots, the scenario as
    run; a path every worker can write): a retried run resumes there from its last snapshot.
    None: a temporary folder, removed afterwards. progress hears the share of the steps done, about
    every CHUNK_WALL_S of wall time. device: where the world steps (World's).
    """
    return simulate(spec.setup, run_dir, progress, device)


def simulate(
    setup: WorldSetup,
    run_dir: Path | None = None,
    progress: ShareDone | None = None,
    device: str = "cpu",
) -> SimOutcome:
    """run_one for a bare setup. A kept run folder gets the simulator's pictures of the swarm
    and its track; a temporary one does not (they would cost more than a small run)."""
    if run_dir is None:
        with tempfile.TemporaryDirectory(prefix="particlebot-study-") as scratch:
            return _run_in(setup, Path(scratch) / "run", False, progress, device)
    return _run_in(setup, run_dir, True, progress, device)


def _run_in(
    setup: WorldSetup,
    folder: Path,
    pictures: bool,
    progress: ShareDone | None = None,
    device: str = "cpu",
) -> SimOutcome:
    framed, run = open_run(setup, folder, pictures, device)
    report = None if progress is None else _share_of_steps(progress)
    return outcome_of(setup, framed, run, run.advance(progress=report), folder)


def open_run(
    setup: WorldSetup, folder: Path, pictures: bool, device: str = "cpu"
) -> tuple[Framed, Run]:
    """A setup's run in folder, resumed from its last snapshot when it has one, else started
    afresh; its world on `device`."""
    framed = frame(setup)
    resumed = (folder / SCENARIO_FILE).is_file() and latest_snapshot(folder) is not None
    if resumed:
        return framed, Run.resume(folder, pictures=pictures, device=device)
    if folder.exists():
        shutil.rmtree(folder)  # a start that died before its first snapshot
    return framed, start_run(framed, folder, pictures, device)


def outcome_of(
    setup: WorldSetup, framed: Framed, run: Run, summary: Summary, folder: Path
) -> SimOutcome:
    """What a finished run gives its study's measure, in the study frame."""
    if not summary.finished:
        raise RuntimeError(f"the run in {folder} stopped at {summary.t_s:g} s")
    dx, dy = framed.offset
    csv = read_published_csv(folder / run.scenario.output.csv_name)
    assert csv.distance_m is not None  # our CSV always has the column
    state = run.world.state()
    final_xy = np.stack([state.x - dx, state.y - dy], axis=1)
    start = end = None
    if (o := setup.passive_object) is not None:
        start = (o.x, o.y)
        end = (float(state.objects[0, 0] - dx), float(state.objects[0, 1] - dy))
    return SimOutcome(
        track=Track(
            csv.time_s, csv.centroid_m[:, 0] - dx, csv.centroid_m[:, 1] - dy, csv.distance_m
        ),
        final_xy=final_xy,
        object_start=start,
        object_end=end,
        summary={
            "steps": float(summary.steps),
            "steps_now": float(summary.steps_now),
            "wall_s": summary.wall_s,
            "particle_steps_per_s": summary.particle_steps_per_s,
            "realtime_factor": summary.realtime_factor,
            "threads": float(summary.threads),
            "resumed_at_s": (summary.steps - summary.steps_now) * run.world.params.dt,
            "turned_deg": framed.turned_deg,
            "offset_x": dx,
            "offset_y": dy,
        },
    )


def _share_of_steps(progress: ShareDone) -> Callable[[Run, float], None]:
    def report(run: Run, _wall_s: float) -> None:
        progress(run.world.steps / max(1, run.total_steps))

    return report


def start_run(framed: Framed, folder: Path, pictures: bool, device: str = "cpu") -> Run:
    """A new run of a framed setup in folder (which must not exist or be empty), its world on
    `device`."""
    scenario = framed.scenario
    with tempfile.TemporaryDirectory(prefix="particlebot-study-") as scratch:
        if framed.positions is not None:
            # A turned placement goes down as a positions file (the run folder keeps a copy, so
            # its scenario.toml reruns it as run).
            path = Path(scratch) / POSITIONS_FILE
            np.savetxt(path, framed.positions, delimiter=",", fmt="%.17g")
            scenario = replace(
                scenario,
                swarm=replace(scenario.swarm, placement=PlacementKind.FILE, file=path),
            )
        try:
            built = build_world(scenario, device=device)
        except ScenarioError as exc:
            raise SetupError(str(exc).replace("study: ", "", 1)) from None
        return Run.start(built, folder, pictures=pictures)
