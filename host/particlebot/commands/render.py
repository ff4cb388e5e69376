"""`particlebot render -o VIDEO [SOURCE]`: a top-view video of a swarm whose centroid is known
(a made-up breathing blob, or a simulator run with per-particle output), and its truth CSV."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from particlebot.commands._common import fail
from particlebot.options import (
    DURATION,
    FRAME_RATE,
    Bounds,
    float_arg,
    int_arg,
)
from particlebot.progress import ProgressBar

if TYPE_CHECKING:
    from particlebot.analysis.synthetic import SwarmFrame

DEFAULT_LAMP_CM = (55.0, 45.0)
LARGEST_SIDE = 8192
"""Pixels: H.264's largest level stops at 8192 x 4320, and no tracker test needs more."""
MOST_FRAMES = 1_000_000
"""A video of more frames (a 55-hour run at 5 fps) is beyond any tracker test."""
BYTES_PER_BODY = 64
"""Memory one particle takes in one frame before rendering (centre, radius and their copies)."""
BYTES_PER_PIXEL = 64
"""Memory one pixel of the frame size takes while a frame is drawn (the floor's map in float64,
its colour channels, the blur's copies)."""

DESCRIPTION = """\
Renders what the paper's camera would film (225 cm above a 285x160 cm field, optionally tilted):
each particle a disc of its current radius, a lamp with its glow, floor mottle, stray reflections,
blur and noise. Writes VIDEO and VIDEO.truth.csv (per frame: the mean of the particles' centres and
the centroid of the region they cover, floor cm, y down). Without SOURCE the swarm is a made-up
blob breathing in a phase-delayed wave and drifting toward the lamp; with SOURCE (a simulator CSV
with per-particle output, or its run folder) the run, interpolated between its rows at --fps."""


def add_arguments(render: argparse.ArgumentParser) -> None:
    render.description = DESCRIPTION
    render.add_argument("source", nargs="?", help="simulator CSV or run folder (default: a blob)")
    render.add_argument("-o", "--output", required=True, help="video to write (.mp4 or .avi)")
    render.add_argument("--size", default="1280x720", help="frame size in pixels (1280x720)")
    render.add_argument(
        "--tilt",
        default="0,0,0",
        metavar="PITCH,ROLL,YAW",
        help="camera tilt in degrees (0,0,0: straight down, so --field fits)",
    )
    render.add_argument(
        "--lamp",
        metavar="X,Y",
        help="lamp on the field, cm (default 55,45; for a run, where its light is, if known)",
    )
    render.add_argument(
        "--noise",
        type=float_arg(Bounds(minimum=0, maximum=255)),
        default=3.0,
        help="sensor noise, grey levels (3)",
    )
    blob = render.add_argument_group("the made-up blob")
    blob.add_argument(
        "--particles", type=int_arg(Bounds(minimum=1)), default=10, help="how many (10)"
    )
    blob.add_argument("--start", default="190,95", metavar="X,Y", help="its centre, field cm")
    blob.add_argument(
        "--speed-mm-s",
        type=float_arg(Bounds(minimum=-1e3, maximum=1e3)),
        default=1.0,
        help="drift toward the lamp (1)",
    )
    blob.add_argument(
        "--duration-s", type=float_arg(DURATION), default=180.0, help="length (180 s)"
    )
    render.add_argument(
        "--fps",
        type=float_arg(FRAME_RATE),
        help="frames per second (5 for the blob, 1 for a run, interpolated)",
    )
    blob.add_argument(
        "--seed", type=int_arg(Bounds(minimum=0, maximum=2**32 - 1)), default=1, help="seed (1)"
    )


def _frames(
    args: argparse.Namespace, lamp: tuple[float, float] | None
) -> tuple[list[SwarmFrame], float, tuple[float, float] | None]:
    """The frames, their rate and the lamp's place on the field."""
    from particlebot.analysis import sources, synthetic
    from particlebot.analysis.geometry import parse_pair
    from particlebot.sim.runs import simcsv

    if args.source is None:
        fps = 5.0 if args.fps is None else args.fps
        _check_size(args.duration_s, fps, args.particles)
        lamp = lamp if lamp is not None else DEFAULT_LAMP_CM
        spec = synthetic.BlobSpec(
            count=args.particles,
            start_cm=parse_pair(args.start, "--start"),
            lamp_cm=lamp,
            speed_mm_s=args.speed_mm_s,
            duration_s=args.duration_s,
            fps=fps,
            seed=args.seed,
        )
        return synthetic.breathing_blob(spec), fps, lamp
    series = sources.load_source(Path(args.source))[0]
    run = simcsv.read_published_csv(series.path)
    start = run.centroid_m[0]
    # The run's start goes where the blob would start, so the lamp's side stays in view.
    placement = synthetic.Placement(
        (float(start[0]), float(start[1])), parse_pair(args.start, "--start")
    )
    fps = 1.0 if args.fps is None else args.fps
    _check_size(float(run.time_s[-1] - run.time_s[0]), fps, run.particles)
    frames = synthetic.frames_from_run(run, placement, fps)
    if lamp is None and series.lamp_cm is not None:
        lx, ly = placement.to_field(series.lamp_cm[0] / 100, series.lamp_cm[1] / 100)
        lamp = (float(lx), float(ly))
    return frames, fps, lamp


def _check_size(duration_s: float, fps: float, particles: int) -> None:
    """TooBigError before any frame is made when the video has too many frames or its frames
    would not fit in memory."""
    from particlebot.machine import TooBigError, check_memory

    count = duration_s * fps + 1
    if count > MOST_FRAMES:
        raise TooBigError(
            f"{duration_s:g} s at {fps:g} fps is {count:.3g} frames; at most {MOST_FRAMES:,}"
        )
    check_memory(
        count * particles * BYTES_PER_BODY, f"{count:,.0f} frames of {particles:,} particles"
    )


def run(args: argparse.Namespace) -> int:
    from particlebot.analysis.camera import Camera
    from particlebot.analysis.geometry import GeometryError, parse_pair
    from particlebot.analysis.render import Scene, render_video, write_truth
    from particlebot.analysis.sources import SourceError
    from particlebot.analysis.video import VideoError
    from particlebot.machine import check_memory
    from particlebot.sim.runs.simcsv import SimFormatError

    output = Path(args.output)
    try:
        width, height = (int(v) for v in parse_pair(args.size, "--size", "x"))
        if not (64 <= width <= LARGEST_SIDE and 64 <= height <= LARGEST_SIDE):
            raise ValueError(f"--size must be 64x64 to {LARGEST_SIDE}x{LARGEST_SIDE}")
        check_memory(width * height * BYTES_PER_PIXEL, f"frames of {width}x{height}")
        tilt = [float(v) for v in args.tilt.split(",")]
        if len(tilt) != 3:
            raise ValueError("--tilt must be PITCH,ROLL,YAW in degrees")
        frames, fps, lamp = _frames(args, parse_pair(args.lamp, "--lamp") if args.lamp else None)
        camera = Camera.paper((width, height), pitch_deg=tilt[0], roll_deg=tilt[1], yaw_deg=tilt[2])
        scene = Scene(camera, lamp_cm=lamp, noise_sigma=args.noise, seed=args.seed)
        bar = ProgressBar(f"render {output.name}", len(frames))
        try:
            result = render_video(frames, scene, output, fps, progress=bar.update)
        finally:
            bar.finish()
    except (GeometryError, VideoError, SourceError, SimFormatError, ValueError) as exc:
        return fail(str(exc))
    truth_path = output.with_suffix(".truth.csv")
    write_truth(truth_path, result.truth)
    print(f"Video: {output} ({result.frames} frames at {fps:g} fps, {width}x{height})")
    print(f"Truth: {truth_path}")
    print("Lamp: none" if lamp is None else f"Lamp: ({lamp[0]:g}, {lamp[1]:g}) cm on the field")
    corners = [(0.0, 0.0), (285.0, 0.0), (285.0, 160.0), (0.0, 160.0)]
    pixels = camera.project(corners)
    points = " ".join(
        f"--point={u:.1f},{v:.1f}={x:g},{y:g}"
        for (u, v), (x, y) in zip(pixels, corners, strict=True)
    )
    if any(tilt):
        print(f"Track it with the field's corners: particlebot track {output} {points}")
    else:
        print(f"Track it with: particlebot track {output}")
    return 0
