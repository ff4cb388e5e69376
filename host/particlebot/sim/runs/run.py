"""One simulated run in its folder: the scenario as run, the published CSV, snapshots to resume
from, pictures and (when asked) a video. Outputs are observers of the world, never code inside
its step loop; a stop between two chunks of steps leaves a snapshot to resume from.

A run folder holds:
  scenario.toml      the scenario as run (`particlebot simulate scenario.toml` reruns it)
  published.cfg      the same in the published simulator's format (as far as it goes)
  <csv>              the published CSV (run.csv unless the scenario names it)
  snapshots/step-NNNNNNNNN.npz   the world every snapshot interval, at the end and at a stop
  swarm-start.png, swarm.png     the swarm from above at the start and at the end (or stop)
  track.png          the centroid's path and its distance to the lamp
  frames/, <video>   with --video: the frames, then the MP4 or GIF made of them
  summary.json       the last invocation's figures (as `simulate --json` prints them)
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from particlebot.analysis.simcsv import SimFormatError, read_published_csv
from particlebot.errors import ParticlebotError
from particlebot.sim.runs import video
from particlebot.sim.runs.csvlog import CsvLog
from particlebot.sim.runs.pictures import Frame, View, save_swarm_picture, save_track_plot
from particlebot.sim.scenarios.build import Built
from particlebot.sim.scenarios.scenario import PlacementKind, Scenario
from particlebot.sim.scenarios.toml_file import read_scenario
from particlebot.sim.scenarios.write import to_published_cfg, to_toml
from particlebot.sim.world.world import Snapshot, World

SCENARIO_FILE = "scenario.toml"
PUBLISHED_FILE = "published.cfg"
SNAPSHOTS = "snapshots"
FRAMES = "frames"
SUMMARY_FILE = "summary.json"
STATE_FILE = "run.json"
START_PICTURE = "swarm-start.png"
END_PICTURE = "swarm.png"
TRACK_PICTURE = "track.png"
CHUNK_WALL_S = 0.25
"""Steps are taken in chunks of about this much wall time: progress and a stop act between."""


class RunError(ParticlebotError, ValueError):
    """A run folder that cannot be used: taken, or not a run to resume."""


class BlownUpError(RunError):
    """The world's state stopped being finite numbers: the run stops at the last good snapshot."""


@dataclass
class Summary:
    """What one invocation did, as `simulate --json` prints it (SI units)."""

    particles: int
    objects: int
    steps: int
    """Steps of the run so far (all invocations)."""
    steps_now: int
    """Steps this invocation took."""
    t_s: float
    wall_s: float
    particle_steps_per_s: float
    realtime_factor: float
    threads: int
    """Threads the steps ran on (1 below World's PARALLEL_FROM particles)."""
    centroid_start: tuple[float, float]
    centroid_end: tuple[float, float]
    distance_to_light_start: float
    distance_to_light_end: float
    speed_toward_light_mm_s: float
    finished: bool
    run_folder: str
    csv: str
    snapshot: str

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["centroid_start"] = list(self.centroid_start)
        data["centroid_end"] = list(self.centroid_end)
        return data


def default_folder(name: str, root: Path = Path("runs")) -> Path:
    """runs/<name>-<date>-<time>, unique."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    folder = root / f"{name}-{stamp}"
    n = 2
    while folder.exists():
        folder = root / f"{name}-{stamp}-{n}"
        n += 1
    return folder


def latest_snapshot(folder: Path) -> Path | None:
    snapshots = sorted((folder / SNAPSHOTS).glob("step-*.npz"))
    return snapshots[-1] if snapshots else None


def check_run_folder(folder: Path) -> Path:
    """The latest snapshot of a run folder; RunError when it is not one to resume."""
    if not (folder / SCENARIO_FILE).is_file():
        raise RunError(f"{folder} is not a run folder (no {SCENARIO_FILE})")
    snapshot = latest_snapshot(folder)
    if snapshot is None:
        raise RunError(f"{folder} has no snapshot to resume from ({SNAPSHOTS}/ is empty)")
    return snapshot


class Run:
    """A world stepping toward the end of its scenario, its outputs attached as observers."""

    def __init__(
        self,
        folder: Path,
        scenario: Scenario,
        world: World,
        csv: CsvLog,
        view: View,
        start: tuple[tuple[float, float], float],
        record_video: bool,
        frame_every: int,
    ) -> None:
        self.folder = folder
        self.scenario = scenario
        self.world = world
        self.csv = csv
        self.view = view
        self.start_centroid, self.start_distance = start
        self.record_video = record_video
        self.total_steps = scenario.steps
        self._frame_every = frame_every
        self._snapshot_step = -1
        self.pictures = True
        """Draw swarm-start.png, swarm.png and track.png (a study's throwaway runs do not: the
        three pictures cost four times a 10-particle half-hour's simulation)."""
        world.add_observer(self._dump, scenario.dump_every)
        world.add_observer(self._periodic_snapshot, scenario.snapshot_every)
        if record_video:
            world.add_observer(self._film, self._frame_every)

    # ---- starting and resuming -------------------------------------------------------------

    @classmethod
    def start(
        cls, built: Built, folder: Path, record_video: bool = False, pictures: bool = True
    ) -> Run:
        """Creates the run folder (which must not exist, or be empty) and writes the start:
        scenario files, the CSV's header and first row, a snapshot, the first picture."""
        if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
            raise RunError(f"{folder} exists and is not empty: resume it with --resume {folder}")
        scenario, world = built.scenario, built.world
        folder.mkdir(parents=True, exist_ok=True)
        (folder / SNAPSHOTS).mkdir()
        if scenario.swarm.placement is PlacementKind.FILE and scenario.swarm.file is not None:
            shutil.copyfile(
                scenario.swarm.file, folder / ("positions" + scenario.swarm.file.suffix)
            )
        _write_scenario(folder, scenario, built.particles)
        start = (world.centroid(), world.light_distance())
        frame_every = video.frame_every(scenario.steps, scenario.output.video_frames)
        _write_state(
            folder,
            {
                "video": record_video,
                "centroid_start": start[0],
                "distance_to_light_start": start[1],
                "particles": built.particles,
                "frame_every": frame_every,
            },
        )
        frame = Frame.of(world)
        view = View.around(frame, (world.lamp.x, world.lamp.y), world.arena, _title(scenario))
        (folder / "view.json").write_text(json.dumps(view.to_json()) + "\n")
        bodies = world.count + len(world.objects)
        csv = CsvLog.create(
            folder / scenario.output.csv_name, scenario.seed, bodies, scenario.output.per_particle
        )
        run = cls(folder, scenario, world, csv, view, start, record_video, frame_every)
        run.pictures = pictures
        run._dump(world)
        run._snapshot()
        if pictures:
            save_swarm_picture(folder / START_PICTURE, frame, view)
        if record_video:
            run._film(world)
        return run

    @classmethod
    def resume(
        cls,
        folder: Path,
        record_video: bool = False,
        duration_s: float | None = None,
        pictures: bool = True,
    ) -> Run:
        """Continues a run from its latest snapshot; the CSV loses the rows written after it
        (the resumed run writes them again, the same). duration_s moves the run's end (later
        or earlier, not before the snapshot), and the folder's scenario says so."""
        snapshot = check_run_folder(folder)
        scenario = read_scenario(folder / SCENARIO_FILE)
        try:
            world = World.from_snapshot(Snapshot.load(snapshot))
        except (OSError, ValueError, KeyError, EOFError) as exc:
            raise RunError(f"{snapshot}: cannot be read ({exc})") from None
        try:
            state = json.loads((folder / STATE_FILE).read_text())
            view_data = json.loads((folder / "view.json").read_text())
            centroid = state["centroid_start"]
            start = (
                (float(centroid[0]), float(centroid[1])),
                float(state["distance_to_light_start"]),
            )
            frame_every = int(state["frame_every"])
            particles = int(state["particles"])
        except (OSError, ValueError, KeyError, TypeError, IndexError) as exc:
            raise RunError(f"{folder}: damaged run files ({exc})") from None
        if duration_s is not None:
            if round(duration_s / world.params.dt) < world.steps:
                raise RunError(
                    f"{folder} is at {world.t:g} s already: give a --duration beyond that"
                )
            scenario = replace(scenario, duration_s=duration_s)
            _write_scenario(folder, scenario, particles)
        view = View.from_json(view_data, world.arena)
        csv_path = folder / scenario.output.csv_name
        if not csv_path.is_file():
            raise RunError(f"{folder}: its CSV {csv_path.name} is missing")
        csv = CsvLog.resume(csv_path, world.t, scenario.output.per_particle)
        record_video = record_video or bool(state.get("video"))
        run = cls(folder, scenario, world, csv, view, start, record_video, frame_every)
        run.pictures = pictures
        run._snapshot_step = world.steps
        if record_video and not state.get("video"):
            _write_state(folder, {**state, "video": True})
        return run

    # ---- observers -----------------------------------------------------------------------------

    def _dump(self, world: World) -> None:
        self.csv.write(world.state(), world.centroid(), world.light_distance())

    def _periodic_snapshot(self, world: World) -> None:
        if world.steps < self.total_steps:
            self._snapshot()

    def _film(self, world: World) -> None:
        video.write_frame(
            self.folder / FRAMES, world.steps // self._frame_every, Frame.of(world), self.view
        )

    def _snapshot(self) -> Path:
        """The world now, for resuming (the World's arrays) and analysis (state_* arrays in the
        particles' own order); written under a temporary name, then renamed."""
        world = self.world
        path = self.folder / SNAPSHOTS / f"step-{world.steps:09d}.npz"
        if self._snapshot_step == world.steps and path.exists():
            return path
        snap = world.snapshot()
        state = world.state()
        snap.arrays.update(
            {
                "state_t": np.array(state.t),
                "state_x": state.x,
                "state_y": state.y,
                "state_vx": state.vx,
                "state_vy": state.vy,
                "state_radius": state.radius,
                "state_alive": state.alive,
                "state_member": state.member,
                "state_free": state.free,
                "state_objects": state.objects,
                "state_phase": np.asarray(world.phase(), dtype=np.float64),
            }
        )
        temporary = path.with_name(".writing.npz")
        snap.save(temporary)
        os.replace(temporary, path)
        self._snapshot_step = world.steps
        return path

    # ---- running -------------------------------------------------------------------------------

    @property
    def finished(self) -> bool:
        return self.world.steps >= self.total_steps

    def advance(
        self,
        should_stop: Callable[[], bool] = lambda: False,
        progress: Callable[[Run, float], None] | None = None,
    ) -> Summary:
        """Steps to the end of the scenario, or until should_stop() says so between chunks;
        then writes the snapshot, pictures (and video) and summary. progress(run, wall_s) is
        called after every chunk."""
        world = self.world
        began = time.monotonic()
        steps_before = world.steps
        chunk = 1
        blown_up = False
        try:
            while not self.finished and not should_stop():
                tick = time.monotonic()
                world.step(min(chunk, self.total_steps - world.steps))
                took = time.monotonic() - tick
                if not world.finite():
                    blown_up = True  # its snapshot would hold NaN: the last good one stays
                    raise BlownUpError(
                        f"the world's state stopped being finite numbers by {world.t:g} s "
                        f"(step {world.steps}): the physics is unstable for these settings; "
                        f"{self.folder} keeps its last good snapshot"
                    )
                # Aim for chunks of CHUNK_WALL_S: progress stays live, a stop acts soon.
                rate = chunk / max(took, 1e-6)
                chunk = max(1, min(int(rate * CHUNK_WALL_S), 4 * chunk))
                if progress is not None:
                    progress(self, time.monotonic() - began)
        finally:
            wall = time.monotonic() - began
            snapshot = None if blown_up else self._snapshot()
            self.csv.close()
        assert snapshot is not None
        return self._finish(wall, world.steps - steps_before, snapshot)

    def _finish(self, wall_s: float, steps_now: int, snapshot: Path) -> Summary:
        world, folder = self.world, self.folder
        csv_path = folder / self.scenario.output.csv_name
        if self.pictures:
            frame = Frame.of(world)
            save_swarm_picture(
                folder / END_PICTURE,
                frame,
                View.around(frame, self.view.lamp, self.view.arena, self.view.title),
            )
            try:
                track = read_published_csv(csv_path)
                save_track_plot(folder / TRACK_PICTURE, track, self.view)
            except SimFormatError:
                pass  # no rows yet beyond the header: nothing to plot
        if self.record_video and self.finished:
            video.encode(folder / FRAMES, folder / self.scenario.output.video_name)
        end = world.centroid()
        distance = world.light_distance()
        simulated = steps_now * world.params.dt
        summary = Summary(
            particles=world.count,
            objects=len(world.objects),
            steps=world.steps,
            steps_now=steps_now,
            t_s=world.t,
            wall_s=wall_s,
            particle_steps_per_s=world.count * steps_now / wall_s if wall_s > 0 else 0.0,
            realtime_factor=simulated / wall_s if wall_s > 0 else 0.0,
            threads=world.threads,
            centroid_start=self.start_centroid,
            centroid_end=end,
            distance_to_light_start=self.start_distance,
            distance_to_light_end=distance,
            speed_toward_light_mm_s=(self.start_distance - distance) / world.t * 1000.0
            if world.t > 0
            else 0.0,
            finished=self.finished,
            run_folder=str(folder),
            csv=str(csv_path),
            snapshot=str(snapshot),
        )
        (folder / SUMMARY_FILE).write_text(json.dumps(summary.to_json(), indent=1) + "\n")
        return summary


def _write_scenario(folder: Path, scenario: Scenario, particles: int) -> None:
    """scenario.toml and published.cfg: the scenario as run (its positions file, if any, is the
    folder's own copy)."""
    positions = None
    if scenario.swarm.placement is PlacementKind.FILE and scenario.swarm.file is not None:
        positions = "positions" + scenario.swarm.file.suffix
    (folder / SCENARIO_FILE).write_text(to_toml(scenario, positions), encoding="utf-8")
    (folder / PUBLISHED_FILE).write_text(to_published_cfg(scenario, particles), encoding="utf-8")


def _write_state(folder: Path, state: dict[str, Any]) -> None:
    """run.json: what a resume needs besides the scenario and the snapshot."""
    (folder / STATE_FILE).write_text(json.dumps(state) + "\n")


def _title(scenario: Scenario) -> str:
    return f"{scenario.name} (seed {scenario.seed})"
