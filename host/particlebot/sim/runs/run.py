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
  trajectory.gsd     with --gsd: every body at every dump interval (HOOMD-blue's GSD)
  trajectory.xyz     with --xyz: the same as extended XYZ
  summary.json       the last invocation's figures (as `simulate --json` prints them)
"""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from particlebot.devices import DeviceError
from particlebot.errors import ParticlebotError
from particlebot.fileio import atomic_path, make_folder, write_text
from particlebot.sim.runs import video
from particlebot.sim.runs.csvlog import CsvDamagedError, CsvLog
from particlebot.sim.runs.pictures import Frame, View, save_swarm_picture, save_track_plot
from particlebot.sim.runs.simcsv import SimFormatError, read_published_csv
from particlebot.sim.runs.trajectory import GSD_FILE, XYZ_FILE, GsdLog, TrajectoryLog, XyzLog
from particlebot.sim.scenarios.build import Built
from particlebot.sim.scenarios.scenario import ControllerKind, PlacementKind, Scenario
from particlebot.sim.scenarios.toml_file import read_scenario
from particlebot.sim.scenarios.write import to_published_cfg, to_toml
from particlebot.sim.world.snapshot import Snapshot, SnapshotError
from particlebot.sim.world.world import World

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
    video: str = ""
    """The film's path, once written ("" without one)."""

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


def claim_run_folder(folder: Path) -> bool:
    """Makes sure a new run can go into `folder` before anything is built for it: RunError when
    it holds something already, OutputError (naming it, and why) when it cannot be created or
    written. Returns whether this call created it (the caller removes it again, empty, if the
    run never starts)."""
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise RunError(f"{folder} exists and is not empty: resume it with --resume {folder}")
    created = not folder.exists()
    make_folder(folder)
    return created


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
        trajectories: tuple[TrajectoryLog, ...] = (),
    ) -> None:
        self.folder = folder
        self.scenario = scenario
        self.world = world
        self.csv = csv
        self.view = view
        self.start_centroid, self.start_distance = start
        self.record_video = record_video
        self.trajectories = trajectories
        self.total_steps = scenario.steps
        self._frame_every = frame_every
        self._snapshot_step = -1
        self.notes: list[str] = []
        """What a resume found worth saying (a damaged snapshot skipped, a view redrawn)."""
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
        cls,
        built: Built,
        folder: Path,
        record_video: bool = False,
        pictures: bool = True,
        trajectory: tuple[str, ...] = (),
    ) -> Run:
        """Creates the run folder (which must not exist, or be empty) and writes the start:
        scenario files, the CSV's header and first row, a snapshot, the first picture.
        trajectory: the formats of the whole trajectory to write ("gsd", "xyz")."""
        if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
            raise RunError(f"{folder} exists and is not empty: resume it with --resume {folder}")
        created = not folder.exists()
        make_folder(folder)
        try:
            return cls._begin(built, folder, record_video, pictures, trajectory)
        except BaseException:
            # Nothing half-written: a folder this call made goes again, whatever stopped it.
            if created:
                shutil.rmtree(folder, ignore_errors=True)
            else:
                for child in folder.iterdir():
                    if child.is_dir():
                        shutil.rmtree(child, ignore_errors=True)
                    else:
                        child.unlink(missing_ok=True)
            raise

    @classmethod
    def _begin(
        cls,
        built: Built,
        folder: Path,
        record_video: bool,
        pictures: bool,
        trajectory: tuple[str, ...],
    ) -> Run:
        scenario, world = built.scenario, built.world
        make_folder(folder / SNAPSHOTS)
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
                "trajectory": list(trajectory),
            },
        )
        frame = Frame.of(world)
        view = View.around(frame, (world.lamp.x, world.lamp.y), world.arena, _title(scenario))
        write_text(folder / "view.json", json.dumps(view.to_json()) + "\n")
        bodies = world.count + len(world.objects)
        csv = CsvLog.create(
            folder / scenario.output.csv_name, scenario.seed, bodies, scenario.output.per_particle
        )
        logs = _trajectory_logs(folder, trajectory)
        run = cls(folder, scenario, world, csv, view, start, record_video, frame_every, logs)
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
        trajectory: tuple[str, ...] = (),
        device: str = "cpu",
    ) -> Run:
        """Continues a run from its latest snapshot that can be read (a damaged later one is
        skipped, with a note); the CSV loses the rows written after it (the resumed run writes
        them again, the same). duration_s moves the run's end (later or earlier, not before the
        snapshot), and the folder's scenario says so. RunError, naming the file, for a folder
        that cannot go on: no readable snapshot, a damaged run.json or CSV, or a scenario.toml
        edited since the run began (another swarm, time step or lamp). trajectory: formats to write
        from now on besides those the run writes already. device: where the world steps."""
        check_run_folder(folder)
        scenario = read_scenario(folder / SCENARIO_FILE)
        world, notes = _latest_world(folder, device)
        state = _read_state(folder)
        try:
            centroid = state["centroid_start"]
            start = (
                (float(centroid[0]), float(centroid[1])),
                float(state["distance_to_light_start"]),
            )
            frame_every = int(state["frame_every"])
            particles = int(state["particles"])
            kinds = [str(kind) for kind in state.get("trajectory", [])]
            if any(kind not in _TRAJECTORY_LOGS for kind in kinds):
                raise ValueError(f"trajectory formats {kinds}")
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            raise RunError(f"{folder / STATE_FILE} is damaged ({exc!r} missing or wrong)") from None
        changed = _changes(scenario, world, particles)
        if changed:
            raise RunError(
                f"{folder / SCENARIO_FILE} was edited since the run began ({'; '.join(changed)}): "
                "a resumed run goes on as it began; run the edited scenario as a new run"
            )
        if duration_s is not None:
            if round(duration_s / world.params.dt) < world.steps:
                raise RunError(
                    f"{folder} is at {world.t:g} s already: give a --duration beyond that"
                )
            scenario = replace(scenario, duration_s=duration_s)
            _write_scenario(folder, scenario, particles)
        view = _read_view(folder, world, scenario, notes)
        csv_path = folder / scenario.output.csv_name
        if not csv_path.is_file():
            raise RunError(f"{folder}: its CSV {csv_path.name} is missing")
        bodies = world.count + len(world.objects)
        try:
            csv, csv_note = CsvLog.resume(
                csv_path, world.t, scenario.output.per_particle, scenario.seed, bodies
            )
        except CsvDamagedError as exc:
            raise RunError(str(exc)) from None
        if csv_note:
            notes.append(csv_note)
        record_video = record_video or bool(state.get("video"))
        kinds += [kind for kind in trajectory if kind not in kinds]
        logs = _trajectory_logs(folder, kinds, resume_at=world.steps)
        run = cls(folder, scenario, world, csv, view, start, record_video, frame_every, logs)
        run.pictures = pictures
        run.notes = notes
        run._snapshot_step = world.steps
        if (record_video and not state.get("video")) or kinds != state.get("trajectory", []):
            _write_state(folder, {**state, "video": record_video, "trajectory": kinds})
        return run

    # ---- observers -----------------------------------------------------------------------------

    def _dump(self, world: World) -> None:
        self.csv.write(world.state(), world.centroid(), world.light_distance())
        for log in self.trajectories:
            log.write(world)

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
        with atomic_path(path) as temporary:
            snap.save(temporary)
        self._snapshot_step = world.steps
        return path

    # ---- running -------------------------------------------------------------------------------

    @property
    def finished(self) -> bool:
        return self.world.steps >= self.total_steps

    @property
    def video_path(self) -> Path:
        return self.folder / self.scenario.output.video_name

    def advance(
        self,
        should_stop: Callable[[], bool] = lambda: False,
        progress: Callable[[Run, float], None] | None = None,
        video_progress: Callable[[int, int], None] | None = None,
    ) -> Summary:
        """Steps to the end of the scenario, or until should_stop() says so between chunks;
        then writes the snapshot, pictures (and video) and summary. progress(run, wall_s) is
        called after every chunk, video_progress(frames done, frames) while the film is
        encoded."""
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
            for log in self.trajectories:
                log.close()
        assert snapshot is not None
        return self._finish(wall, world.steps - steps_before, snapshot, video_progress)

    def _finish(
        self,
        wall_s: float,
        steps_now: int,
        snapshot: Path,
        video_progress: Callable[[int, int], None] | None = None,
    ) -> Summary:
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
        film = ""
        if self.record_video and self.finished:
            film = str(video.encode(folder / FRAMES, self.video_path, progress=video_progress))
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
            video=film,
        )
        write_text(folder / SUMMARY_FILE, json.dumps(summary.to_json(), indent=1) + "\n")
        return summary


_TRAJECTORY_LOGS: dict[str, tuple[str, type[GsdLog] | type[XyzLog]]] = {
    "gsd": (GSD_FILE, GsdLog),
    "xyz": (XYZ_FILE, XyzLog),
}
"""Trajectory format -> its file in the run folder and its writer."""


def _trajectory_logs(
    folder: Path, kinds: Sequence[str], resume_at: int | None = None
) -> tuple[TrajectoryLog, ...]:
    """The run's trajectory files, new or (resume_at: the snapshot's step) continued."""
    logs: list[TrajectoryLog] = []
    for kind in kinds:
        name, writer = _TRAJECTORY_LOGS[kind]
        path = folder / name
        logs.append(writer.create(path) if resume_at is None else writer.resume(path, resume_at))
    return tuple(logs)


def _write_scenario(folder: Path, scenario: Scenario, particles: int) -> None:
    """scenario.toml and published.cfg: the scenario as run (its positions file, if any, is the
    folder's own copy)."""
    positions = None
    if scenario.swarm.placement is PlacementKind.FILE and scenario.swarm.file is not None:
        positions = "positions" + scenario.swarm.file.suffix
    write_text(folder / SCENARIO_FILE, to_toml(scenario, positions))
    write_text(folder / PUBLISHED_FILE, to_published_cfg(scenario, particles))


def _latest_world(folder: Path, device: str = "cpu") -> tuple[World, list[str]]:
    """The world of the latest snapshot that reads whole (on `device`), and a note for each later
    one that does not; RunError when none does."""
    notes: list[str] = []
    for path in sorted((folder / SNAPSHOTS).glob("step-*.npz"), reverse=True):
        try:
            world = World.from_snapshot(Snapshot.load(path), device=device)
        except DeviceError:
            raise
        except SnapshotError as exc:
            notes.append(str(exc))
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            notes.append(f"{path}: damaged ({exc})")
        else:
            if notes:
                notes[-1] += f"; resuming from {path.name}"
            return world, notes
    raise RunError(notes[0] if len(notes) == 1 else f"no snapshot can be read: {notes[0]}")


def _read_state(folder: Path) -> dict[str, Any]:
    path = folder / STATE_FILE
    try:
        state = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RunError(f"{path} is missing") from None
    except (OSError, ValueError) as exc:
        raise RunError(f"{path} is damaged ({exc})") from None
    if not isinstance(state, dict):
        raise RunError(f"{path} is damaged (not a JSON object)")
    return state


def _read_view(folder: Path, world: World, scenario: Scenario, notes: list[str]) -> View:
    """view.json's frame for the pictures; drawn afresh from the world (and the file written
    again) when it is damaged: it is only where the pictures look."""
    path = folder / "view.json"
    try:
        return View.from_json(json.loads(path.read_text(encoding="utf-8")), world.arena)
    except (OSError, ValueError, KeyError, TypeError, IndexError) as exc:
        lamp = (world.lamp.x, world.lamp.y)
        view = View.around(Frame.of(world), lamp, world.arena, _title(scenario))
        write_text(path, json.dumps(view.to_json()) + "\n")
        notes.append(f"{path} was damaged ({type(exc).__name__}); written again from the snapshot")
        return view


def _changes(scenario: Scenario, world: World, particles: int) -> list[str]:
    """What the folder's scenario says differently from the world its snapshot holds."""
    changed = []
    if scenario.swarm.placement is not PlacementKind.FILE and scenario.swarm.particles != particles:
        changed.append(f"swarm.particles {particles} -> {scenario.swarm.particles}")
    for f in fields(scenario.physics):
        was, now = getattr(world.params, f.name), getattr(scenario.physics, f.name)
        if was != now:
            changed.append(f"physics.{f.name} {was} -> {now}")
    if scenario.seed != world.seed:
        changed.append(f"seed {world.seed} -> {scenario.seed}")
    if (scenario.lamp.x, scenario.lamp.y) != (world.lamp.x, world.lamp.y):
        changed.append(
            f"lamp ({world.lamp.x:g}, {world.lamp.y:g}) -> "
            f"({scenario.lamp.x:g}, {scenario.lamp.y:g})"
        )
    settings = getattr(world.controller, "settings", None)
    spec = scenario.controller
    wanted = spec.firmware if spec.kind is ControllerKind.FIRMWARE else spec.published
    if settings is not None and settings != wanted:
        changed.append("[controller]")
    return changed


def _write_state(folder: Path, state: dict[str, Any]) -> None:
    """run.json: what a resume needs besides the scenario and the snapshot."""
    write_text(folder / STATE_FILE, json.dumps(state) + "\n")


def _title(scenario: Scenario) -> str:
    return f"{scenario.name} (seed {scenario.seed})"
