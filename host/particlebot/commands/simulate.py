"""`particlebot simulate [SCENARIO]`: a swarm in the simulated world, from one of our TOML
scenarios, a published simulator configuration file, or a few flags; outputs in a run folder."""

from __future__ import annotations

import argparse
import json
import math
import re
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from particlebot.commands._common import fail
from particlebot.commands._kernels import prepare_kernels
from particlebot.devices import DEVICES
from particlebot.options import (
    DURATION,
    PLACE,
    Bounds,
    OptionError,
    float_arg,
    int_arg,
)
from particlebot.options import parse_float as parse_number
from particlebot.progress import ProgressBar

if TYPE_CHECKING:
    from particlebot.sim.runs.run import Run, Summary
    from particlebot.sim.scenarios.scenario import Scenario

DESCRIPTION = """\
Simulates a swarm of particle robots in the 2-D world (the published simulator's model) and writes
a run folder: the scenario as run, the published CSV (a row every dump interval), snapshots to
resume from, pictures of the swarm and of the centroid's track, and with --video a film.
SCENARIO is one of our TOML scenario files or a configuration file of the published simulator
(read as is); without one, --particles, --duration, --seed, --lamp and --controller describe a
quick run (a blob placed by SI Algorithm 5 walking toward a lamp on its -x side). Ctrl-C stops
after the current chunk of steps and keeps a snapshot: `simulate --resume RUN_FOLDER` goes on."""

LAMP_DIAMETERS = 3.5
"""A quick run's lamp: this many densest-packing diameters of the swarm to its -x side (the
published main puts its light 3.5 packing diameters away)."""
SEEDS = Bounds(minimum=0, maximum=2**63 - 1)
"""A seed is written into the run folder's TOML, whose whole numbers are 64-bit."""
HEIGHT = Bounds(above=0, maximum=PLACE.maximum)
"""A lamp's height (m)."""
HEX_DENSITY = 0.9069
"""Packing fraction of a hexagonal packing of discs, for the swarm's packing diameter."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = DESCRIPTION
    # `--lamp -4,0`: argparse takes "-4,0" for an option unless it looks like a negative number
    # to it, and its own pattern knows no commas (Python 3.13 widened it the same way).
    parser._negative_number_matcher = re.compile(r"^-\d[\d.,eE+-]*$")
    parser.add_argument("scenario", nargs="?", help="our .toml scenario or a published .cfg")
    quick = parser.add_argument_group("a run without a file, or changes to the file's")
    quick.add_argument(
        "--particles", type=int_arg(Bounds(minimum=1)), metavar="N", help="swarm size (10)"
    )
    quick.add_argument(
        "--duration", type=float_arg(DURATION), metavar="S", help="simulated seconds (600)"
    )
    quick.add_argument("--seed", type=int_arg(SEEDS), metavar="K", help="random seed (0)")
    quick.add_argument(
        "--controller",
        choices=("published", "firmware"),
        help="the published light wave (default) or what our firmware does",
    )
    quick.add_argument(
        "--lamp",
        metavar="X,Y[,H]",
        help="lamp position and height, m (default: 3.5 packing diameters toward -x, 0.28 m up)",
    )
    quick.add_argument(
        "--dump-interval", type=float_arg(DURATION), metavar="S", help="CSV row interval (60)"
    )
    quick.add_argument(
        "--per-particle", action="store_true", help="every particle's x, y, vx, vy, r in the CSV"
    )
    parser.add_argument("-o", "--output", metavar="RUN_FOLDER", help="default runs/NAME-DATE-TIME")
    parser.add_argument("--video", action="store_true", help="also film the run (MP4 or GIF)")
    parser.add_argument(
        "--gsd",
        action="store_true",
        help="also write every body at every dump interval to trajectory.gsd (HOOMD-blue's GSD, "
        "which OVITO, freud and MDAnalysis open)",
    )
    parser.add_argument(
        "--xyz", action="store_true", help="also write the trajectory as extended XYZ"
    )
    parser.add_argument(
        "--resume",
        metavar="RUN_FOLDER",
        help="continue a stopped run (with --duration: to a new end)",
    )
    parser.add_argument(
        "--json", action="store_true", help="end with one JSON line of the run's figures"
    )
    parser.add_argument(
        "--device",
        choices=DEVICES,
        default="auto",
        help="where the world steps: the CPU, a CUDA GPU, or auto (the GPU when there is one; "
        "default)",
    )
    parser.add_argument(
        "--threads",
        type=int_arg(Bounds(minimum=1)),
        metavar="N",
        help="threads for swarms of 2,048 particles and more (default: one, or one per core "
        "where that measures faster on this machine as the run goes)",
    )


def _lamp(text: str) -> tuple[float, float, float | None]:
    parts = text.split(",")
    if len(parts) not in (2, 3):
        raise OptionError(f"must be X,Y or X,Y,H in metres, not '{text}'")
    x, y = parse_number(parts[0], PLACE), parse_number(parts[1], PLACE)
    height = parse_number(parts[2], HEIGHT) if len(parts) == 3 else None
    return x, y, height


def quick_scenario(particles: int) -> Scenario:
    """A blob of `particles` (Algorithm 5 from the origin) and a lamp on its -x side."""
    from particlebot.sim.scenarios.scenario import LampSpec, Scenario, SwarmSpec

    scenario = Scenario(name=f"swarm{particles}", swarm=SwarmSpec(particles=particles))
    packing_diameter = 2 * scenario.physics.r_min * math.sqrt(particles / HEX_DENSITY)
    return replace(scenario, lamp=LampSpec(x=-max(1.0, LAMP_DIAMETERS * packing_diameter)))


def load_scenario(path: Path) -> Scenario:
    """Our TOML or a published .cfg, told apart by suffix, else by content."""
    from particlebot.sim.scenarios.published_cfg import (
        looks_like_published_cfg,
        read_published_cfg,
    )
    from particlebot.sim.scenarios.scenario import ScenarioError
    from particlebot.sim.scenarios.toml_file import read_scenario

    if not path.is_file():
        raise ScenarioError(f"no such scenario file: {path}")
    suffix = path.suffix.lower()
    if suffix == ".toml":
        return read_scenario(path)
    if suffix == ".cfg":
        return read_published_cfg(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"cannot read {path}: {exc}") from None
    return read_published_cfg(path) if looks_like_published_cfg(text) else read_scenario(path)


def with_flags(scenario: Scenario, args: argparse.Namespace) -> Scenario:
    """The scenario with what the flags change."""
    from particlebot.sim.scenarios.scenario import (
        ControllerKind,
        LampSpec,
        PlacementKind,
        ScenarioError,
    )

    if args.particles is not None:
        if scenario.swarm.placement is PlacementKind.FILE:
            raise ScenarioError("--particles: this scenario's positions come from a file")
        scenario = replace(scenario, swarm=replace(scenario.swarm, particles=args.particles))
    if args.duration is not None:
        scenario = replace(scenario, duration_s=args.duration)
    if args.seed is not None:
        scenario = replace(scenario, seed=args.seed)
    if args.controller is not None:
        controller = replace(scenario.controller, kind=ControllerKind(args.controller))
        scenario = replace(scenario, controller=controller)
    if args.lamp is not None:
        try:
            x, y, height = _lamp(args.lamp)
        except OptionError as exc:
            raise ScenarioError(f"--lamp: {exc}") from None
        scenario = replace(scenario, lamp=LampSpec(x, y, height))
    if args.dump_interval is not None:
        scenario = replace(
            scenario, output=replace(scenario.output, dump_interval_s=args.dump_interval)
        )
    if args.per_particle:
        scenario = replace(scenario, output=replace(scenario.output, per_particle=True))
    return scenario


@contextmanager
def stop_requests() -> Iterator[Callable[[], bool]]:
    """Ctrl-C and SIGTERM ask the run to stop between two chunks of steps (never inside one,
    where the world's state is half-updated)."""
    asked = False

    def handler(signum: int, frame: FrameType | None) -> None:
        nonlocal asked
        asked = True

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: asked
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def run(args: argparse.Namespace) -> int:
    from particlebot.devices import DeviceError
    from particlebot.sim.runs.run import (
        Run,
        RunError,
        check_run_folder,
        claim_run_folder,
        default_folder,
    )
    from particlebot.sim.runs.video import VideoError
    from particlebot.sim.scenarios.scenario import ScenarioError

    try:
        if args.threads is not None:
            _use_threads(args.threads)
        if args.resume is not None:
            if args.scenario is not None or _changes(args):
                raise ScenarioError(
                    "--resume continues a run as it was: give no scenario, and of the flags "
                    "only --duration (a new end), --video, --gsd, --xyz, --threads or --json"
                )
            folder = Path(args.resume)
            check_run_folder(folder)
            prepare_kernels()
            session = Run.resume(
                folder,
                record_video=args.video,
                duration_s=args.duration,
                trajectory=_trajectory(args),
                device=args.device,
            )
            # Said once the folder has been read: a folder that cannot go on is one line alone.
            print(f"resuming {folder} at {session.world.t:g} s", file=sys.stderr)
            for note in session.notes:
                print(f"note: {note}", file=sys.stderr)
        else:
            from particlebot.sim.scenarios.build import build_world

            if args.scenario is not None:
                scenario = load_scenario(Path(args.scenario))
            else:
                scenario = quick_scenario(args.particles if args.particles is not None else 10)
            scenario = with_flags(scenario, args)
            # What can be refused is, before the kernels load: a refusal is one line.
            scenario.check_feasible()
            folder = Path(args.output) if args.output else default_folder(scenario.name)
            created = claim_run_folder(folder)
            try:
                prepare_kernels()
                print(
                    f"building {scenario.name}: {scenario.swarm.particles} particles",
                    file=sys.stderr,
                )
                built = build_world(scenario, device=args.device)
                for note in built.notes:
                    print(f"note: {note}", file=sys.stderr)
                session = Run.start(
                    built, folder, record_video=args.video, trajectory=_trajectory(args)
                )
            except BaseException:
                if created and folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()  # nothing of this run was written: no folder either
                raise
        session.world.thread_count = args.threads  # None: the world measures and chooses
        summary = _advance(session)
    except (ScenarioError, RunError, DeviceError) as exc:
        return fail(f"simulate: {exc}")
    except VideoError as exc:
        return fail(f"simulate: {exc} (the run itself is complete in its folder)")
    except KeyboardInterrupt:
        print("particlebot: simulate: stopped before the run began", file=sys.stderr)
        return 130
    _report(summary, args.json)
    return 0 if summary.finished else 130


def _trajectory(args: argparse.Namespace) -> tuple[str, ...]:
    return tuple(kind for kind, asked in (("gsd", args.gsd), ("xyz", args.xyz)) if asked)


def _use_threads(threads: int) -> None:
    """Checks an explicit --threads against what numba runs here. Without one, the world picks
    between one thread and one per core from the step times it measures (sim/world/threads.py):
    a parallel step waits at each barrier for a thread another process may hold, so on a busy
    machine one thread can be many times faster (on two cores, two-thread runs side by side
    made 20-118 steps/s of a 10,000-particle swarm, a one-thread run beside them ~1,250)."""
    import numba

    from particlebot.sim.scenarios.scenario import ScenarioError

    most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # set at import
    if threads > most:
        raise ScenarioError(
            f"--threads {threads}: numba here runs at most {most} (one per core, or "
            "NUMBA_NUM_THREADS)"
        )


def _changes(args: argparse.Namespace) -> bool:
    flags = (
        args.particles, args.seed, args.controller, args.lamp, args.dump_interval, args.output,
    )  # fmt: skip
    return any(flag is not None for flag in flags) or args.per_particle


def _advance(session: Run) -> Summary:
    world = session.world
    dt = world.params.dt
    begun_s = world.t
    remaining_s = max(0.0, session.total_steps * dt - begun_s)
    label = f"simulate {session.scenario.name}"
    if begun_s > 0:
        label += f" (from {begun_s:g} s)"
    # A line every few seconds of wall time whatever the swarm's size (the run reports after
    # every chunk of about a quarter second, the bar's ticker in between), the ETA from the
    # wall-clock rate since the first chunk.
    decimals = 0 if remaining_s >= 100 else 1 if remaining_s >= 10 else 2
    bar = ProgressBar(label, remaining_s, unit="s simulated", decimals=decimals)

    def progress(run: Run, wall_s: float) -> None:
        done_s = run.world.t - begun_s
        factor = done_s / wall_s if wall_s > 0 else 0.0
        bar.update(done_s, f"{factor:.1f}x real time, {run.world.count} particles")

    video_bar: ProgressBar | None = None

    def video_progress(done: int, total: int) -> None:
        nonlocal video_bar
        if video_bar is None:
            bar.finish()  # the steps are done: their line ends before the film's begins
            video_bar = ProgressBar(f"video {session.video_path.name}", total)
            video_bar.start()
        video_bar.update(done)

    with stop_requests() as stop:
        bar.start(show_now=False)
        try:
            summary = session.advance(stop, progress, video_progress=video_progress)
        finally:
            bar.finish()
            if video_bar is not None:
                video_bar.finish()
    return summary


def _report(summary: Summary, as_json: bool) -> None:
    print(f"Run folder: {summary.run_folder}")
    if summary.video:
        print(f"Video: {summary.video}")
    print(
        f"{summary.particles} particles, {summary.t_s:g} s simulated ({summary.steps} steps): "
        f"{summary.steps_now} steps in {summary.wall_s:.1f} s, "
        f"{summary.particle_steps_per_s:.3g} particle-steps/s, "
        f"{summary.realtime_factor:.1f}x real time"
    )
    print(
        f"centroid to lamp: {summary.distance_to_light_start:.3f} m -> "
        f"{summary.distance_to_light_end:.3f} m "
        f"({summary.speed_toward_light_mm_s:.3f} mm/s toward it)"
    )
    if not summary.finished:
        print(f"stopped; continue with: particlebot simulate --resume {summary.run_folder}")
    if as_json:
        print(json.dumps(summary.to_json()))
